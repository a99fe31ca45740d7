"""Training batches made by worker processes, for a machine whose training device outruns one CPU core's zoo.

On an H200 the 128² stage ran 0.58 s a step with the zoo, CutMix and the condition maps made in the training
loop: the GPU waited.  With ``TrainConfig.workers`` = W > 0, W processes make the batches ahead of the loop, each
with one torch and one numba thread.  Batch k is drawn from its own generator ``default_rng([seed, k])``, so it
depends on the run's seed and k alone: not on W, not on which worker made it, and a resumed run gets the batches an
uninterrupted one would have.  (With W = 0 the loop draws from the run's single generator, as it always did; the two
modes give different, equally random, streams.)

Each item: images float32 (B, 1, S, S) in [0, 1], class ids int64 (B,), conditions float32 (B, P), CutMix source
map int64 (B, S, S) (:func:`.cutmix.cutmix_sources`).
"""
from __future__ import annotations

import numpy as np
import torch
from torch.utils.data import DataLoader, IterableDataset, get_worker_info

from . import zoo
from .cutmix import cutmix_sources

__all__ = ["batch_at", "worker_batches", "worker_loader"]


def batch_at(cfg, k: int) -> tuple:
    """Batch number ``k`` of a run with config ``cfg`` (see the module), made on the CPU."""
    rng = np.random.default_rng([cfg.seed, k])
    sampler = zoo.ZooSampler(cfg.size, cfg.classes, cfg.seeds_per_set, cfg.sets_per_class, rng=rng,
                             device=torch.device("cpu"), class_weights=cfg.class_weights)
    imgs, ids, conds = sampler.batch(cfg.batch)
    return imgs, ids, conds, cutmix_sources(ids, cfg.size, cfg.size, rng, p=cfg.cutmix_p)


class _Stream(IterableDataset):
    def __init__(self, cfg, start: int, end: int):
        self.cfg, self.start, self.end = cfg, start, end

    def __iter__(self):
        info = get_worker_info()
        w, n = (info.id, info.num_workers) if info is not None else (0, 1)
        # worker w makes batches start + w, start + w + n, ...; the loader takes one from each worker in turn,
        # so the loop receives them in order
        for k in range(self.start + w, self.end, n):
            yield batch_at(self.cfg, k)


def _one_thread(_):
    torch.set_num_threads(1)
    try:
        import numba

        numba.set_num_threads(1)
    except ImportError:
        pass


# Seconds the loop waits for the next batch before it stops with an error instead of waiting for ever.  A 128²
# batch of 64 took the H200 machine's training loop 0.58 s in all; a worker that makes nothing for 2 minutes is stuck.
BATCH_TIMEOUT_S = 120


def worker_batches(cfg, start: int, end: int, pin: bool = False):
    """An iterator over batches ``start`` .. ``end - 1`` made by ``cfg.workers`` processes.

    The workers are *spawned*, not forked.  On an H200 machine forked workers deadlocked before their first batch (0 % CPU,
    each stopped inside a torch op of the zoo): the training process had already started CUDA's and torch's threads,
    and a fork copies their held locks but not the threads that would release them.  A spawned worker starts a fresh
    interpreter and imports what it needs (a few seconds, once per run).  A batch that does not come within
    :data:`BATCH_TIMEOUT_S` ends the iteration with a one-line RuntimeError naming the step and the way out."""
    k = start
    try:
        for item in worker_loader(cfg, start, end, pin):
            yield item
            k += 1
    except RuntimeError as e:
        if "timed out" not in str(e):  # DataLoader's own words for its timeout
            raise
        raise RuntimeError(f"data workers made no batch in {BATCH_TIMEOUT_S} s at step {k + 1} "
                           f"(workers={cfg.workers}); set workers to 0 to make batches in the loop") from e


def worker_loader(cfg, start: int, end: int, pin: bool = False) -> DataLoader:
    """The loader behind :func:`worker_batches`."""
    return DataLoader(_Stream(cfg, start, end), batch_size=None, num_workers=cfg.workers, worker_init_fn=_one_thread,
                      prefetch_factor=4, pin_memory=pin, multiprocessing_context="spawn", timeout=BATCH_TIMEOUT_S)
