"""Job files on a Dask cluster: `omninoise bake JOB.toml --workers N` or `--cluster ADDRESS`.

The same bakes as a one-machine `omninoise bake`, spread over Dask distributed workers; scheduling, transport
and retries are Dask's. Imported only when one of those flags is given (Dask is the `farm` extra, never needed
by the Blender extension).

Units of work, each independent:

- a file: one output, or one frame of a sequence (images, neural and solid bakes, small volumes); the worker
  bakes it with the one-machine code (:func:`backend.bake.bake_frame`) and writes it atomically into the output
  folder (shared storage on a farm), returning its size and sha256;
- a brick: a z range of one large volume (more voxels than ``brick_voxels``, chosen from the workers' memory);
  the worker returns the brick's grids (:func:`backend.bake.volume_channels`) and the client assembles the
  bricks into one sparse OpenVDB file, voxel for voxel the file a one-machine bake writes.

The client checks every result (the file exists with the reported size and hash), removes what a killed
worker left half-written, and keeps a manifest beside the job (``JOB.manifest.json``: per output its bake,
frame, key, size and sha256). A rerun skips outputs that are up to date: files that carry the bake's key in
their metadata, or (``.npy``) whose manifest entry has the key and the file still has the recorded hash;
``force`` redoes them. A worker killed mid-task makes Dask run the task elsewhere (``retries`` more times for
errors raised by the task itself).

Workers import this package, so every worker needs the backend installed (``pip install .[farm]``) and the
job's folder, its inputs and its output root at the same paths (shared storage).
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import time
import uuid
from dataclasses import dataclass

import numpy as np

from omninoise.backend.bake import BakeSpec, KEY_NAME, bake_frame, evaluate_rows, frame_path, volume_channels, volume_grids
from omninoise.backend.jobs import JobError, JobOutcome, load_job, select_bakes

__all__ = ["Task", "plan", "run_farm", "local_client", "remote_client", "brick_voxels_for", "CRASH_ENV"]

#: fault injection for the test that kills a worker mid-task: a worker that finds the file this variable names
#: deletes it, leaves a partial temporary beside its output and exits at once (as a killed process would)
CRASH_ENV = "OMNINOISE_FARM_CRASH_ONCE"
BYTES_PER_VOXEL = 96   #: worker memory one brick voxel may need: values, rgba, density, colour, temperature, copies


@dataclass(frozen=True)
class Task:
    """One unit of work: the file of ``frame`` of bake ``bake`` (None: its single output), or with ``brick``
    the z range (z0, z1) of that volume."""
    bake: str
    frame: int | None
    path: str
    brick: tuple | None = None


def file_record(path: str) -> dict:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return dict(path=path, bytes=os.path.getsize(path), sha256=h.hexdigest())


# -- the worker side --------------------------------------------------------------------------------------

_SPECS: dict = {}


def _job_spec(job: str, bake: str) -> BakeSpec:
    """The bake ``bake`` of job file ``job``, parsed once per worker process (and again if the file changes)."""
    key = (job, os.path.getmtime(job))
    if key not in _SPECS:
        _SPECS.clear()
        _SPECS[key] = {n: s for n, s in load_job(job)}
    spec = _SPECS[key][bake]
    if isinstance(spec, JobError):
        raise spec
    return spec


def _maybe_crash(path: str, tag: str) -> None:
    marker = os.environ.get(CRASH_ENV)
    if not marker or not os.path.exists(marker):
        return
    try:
        os.remove(marker)
    except OSError:
        return  # another worker took it
    from omninoise import export

    partial = os.path.join(os.path.dirname(path), export.partial_prefix(path, tag) + "crash")
    with open(partial, "wb") as fh:
        fh.write(b"half a file")
    os._exit(70)


def _worker_precision(precision: str) -> None:
    """The client's --precision on this worker (every worker of a farm runs the neural denoiser alike)."""
    from omninoise.backend.neural.precision import set_default_precision

    set_default_precision(precision)


def run_file(job: str, bake: str, frame, tag: str, precision: str = "fp32") -> dict:
    """Worker: bake one file (whatever its state), its temporaries under the farm run's ``tag`` -> :func:`file_record`
    of it."""
    from omninoise import export

    _worker_precision(precision)
    spec = _job_spec(job, bake)
    path = frame_path(spec.output, frame)
    _maybe_crash(path, tag)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with export.tagged(tag):
        return file_record(bake_frame(spec, frame))


def run_brick(job: str, bake: str, frame, z0: int, z1: int, tag: str, precision: str = "fp32") -> dict:
    """Worker: the grids of z = z0 .. z1 - 1 of a volume -> {grid name: float32 slab (z1 - z0, ny, nx[, 3])}."""
    _worker_precision(precision)
    spec = _job_spec(job, bake)
    _maybe_crash(frame_path(spec.output, frame), tag)
    return volume_channels(spec, evaluate_rows(spec.source, spec.grid, spec.frame_time(frame), z0, z1))


# -- the client side --------------------------------------------------------------------------------------

def manifest_path(job: str) -> str:
    return os.path.splitext(os.path.abspath(job))[0] + ".manifest.json"


def read_manifest(job: str) -> dict:
    try:
        with open(manifest_path(job), encoding="utf-8") as fh:
            doc = json.load(fh)
        return doc.get("outputs", {}) if isinstance(doc, dict) else {}
    except (OSError, ValueError):
        return {}


def _up_to_date(spec: BakeSpec, frame, manifest: dict) -> bool:
    key = spec.key(frame)
    path = frame_path(spec.output, frame)
    if os.path.splitext(path)[1].lower() != ".npy":
        return spec.is_up_to_date(frame, key)
    rec = manifest.get(os.path.abspath(path))
    if not rec or rec.get("key") != key or not os.path.isfile(path) or os.path.getsize(path) != rec.get("bytes"):
        return False
    return file_record(path)["sha256"] == rec.get("sha256")


def plan(entries: list, force: bool, brick_voxels: int, manifest: dict) -> tuple:
    """(tasks, skipped paths, {path: (spec, frame, n_bricks)}) for valid ``entries`` [(name, spec)]."""
    tasks, skipped, volumes = [], [], {}
    for name, spec in entries:
        for frame in spec.frame_list():
            path = frame_path(spec.output, frame)
            if not force and _up_to_date(spec, frame, manifest):
                skipped.append(path)
                continue
            g = spec.grid
            big = g.rank == 3 and path.lower().endswith(".vdb") and int(np.prod(g.shape)) > brick_voxels
            if not big:
                tasks.append(Task(name, frame, path))
                continue
            per = max(1, brick_voxels // int(np.prod(g.shape[1:])))
            bricks = [(z, min(g.shape[0], z + per)) for z in range(0, g.shape[0], per)]
            volumes[path] = (spec, frame, len(bricks))
            tasks += [Task(name, frame, path, b) for b in bricks]
    return tasks, skipped, volumes


def brick_voxels_for(client, default: int = 1 << 24) -> int:
    """Voxels per brick so that one brick's grids fit comfortably in the smallest worker's memory limit."""
    try:
        limits = [w.get("memory_limit") or 0 for w in client.scheduler_info()["workers"].values()]
    except Exception:  # noqa: BLE001  (an old or unusual scheduler: keep the default)
        return default
    limits = [m for m in limits if m > 0]
    return max(1 << 12, int(min(limits) // BYTES_PER_VOXEL // 4)) if limits else default


def local_client(workers: int, memory_limit: str = "auto"):
    """A local cluster of ``workers`` processes (one thread each) listening on 127.0.0.1 only -> Client."""
    from distributed import Client, LocalCluster

    from omninoise.cli import hugepages

    # the workers are new processes: they start with huge pages for large neural images (cli/hugepages.py)
    os.environ.update(hugepages.environment(os.environ))
    cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", memory_limit=memory_limit,
                           silence_logs=logging.ERROR)
    return Client(cluster)


#: seconds a scheduler has to take a connection and greet it (Dask's own connect timeout, and the greeting's)
CONNECT_TIMEOUT = 30.0


def refused(address: str) -> bool:
    """Whether ``address`` (``tcp://HOST:PORT``, ``tls://HOST:PORT`` or ``HOST:PORT``) refuses a connection now:
    its host answers that nothing listens on the port (a scheduler not started yet, or a wrong port)."""
    import socket

    from .common import split_address

    _, host, port = split_address(address)
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=2.0):
            return False
    except ConnectionRefusedError:
        return True
    except (OSError, ValueError):       # unreachable, slow or unnamed: Dask's own connection says what it finds
        return False


def probe_scheduler(address: str, security=None, timeout: float | None = None, note=None) -> None:
    """Connect to ``address`` as Dask's client does and close again; OSError where no Dask scheduler greets it within
    ``timeout`` (:data:`CONNECT_TIMEOUT`) seconds.  Dask's own connection waits for a scheduler's greeting without a
    deadline, so a server that says nothing (a web server, such as a scheduler's dashboard) holds it for ever, and
    one that says something else can make it read any length (an internal error allocating exabytes).  Where
    nothing listens on the port yet, Dask tries again until the timeout (a scheduler may be starting):
    ``note(text)`` is told so first, and the error says the port refused."""
    import asyncio

    from distributed.comm import connect

    timeout = CONNECT_TIMEOUT if timeout is None else float(timeout)
    args = security.get_connection_args("client") if security is not None else {}
    waiting = refused(address)
    if waiting and note is not None:
        note(f"nothing listens at {address} yet; waiting up to {timeout:g} s for a scheduler to start")

    async def greet():
        comm = await connect(address, timeout=timeout, **args)
        await comm.close()

    async def within():
        try:
            await asyncio.wait_for(greet(), timeout + 1.0)
        except asyncio.TimeoutError:
            return f"it took the connection but sent nothing in {timeout:g} s, where a Dask scheduler greets at once"
        except OSError as exc:      # refused, unreachable, timed out connecting: Dask's own words
            if waiting and refused(address):
                raise OSError(f"nothing listens on its port (the connection was refused for {timeout:g} s): start "
                              "the scheduler (dask scheduler) or check the address") from exc
            raise
        except Exception:  # noqa: BLE001  (a greeting Dask cannot read: any of its decoders' errors)
            return "it answered, but not as a Dask scheduler does"
        return None

    said = asyncio.run(within())
    if said is not None:
        raise OSError(f"{said} (a web page's port, such as the dashboard's? a scheduler listens on port 8786 "
                      "unless told otherwise)")


def remote_client(address: str, tls_ca: str | None = None, tls_cert: str | None = None, tls_key: str | None = None,
                  note=None):
    """A client of a running scheduler, once :func:`probe_scheduler` finds one greeting at ``address``; ``tls://``
    addresses take Dask's Security from the certificate files.  ``note(text)``: :func:`probe_scheduler`'s."""
    from distributed import Client

    security = None
    if tls_ca or tls_cert or tls_key or address.startswith("tls://"):
        from distributed.security import Security

        if not (tls_ca and tls_cert and tls_key):
            raise JobError("a tls:// scheduler needs --tls-ca-file, --tls-cert and --tls-key")
        security = Security(tls_ca_file=tls_ca, tls_client_cert=tls_cert, tls_client_key=tls_key,
                            require_encryption=True)
    probe_scheduler(address, security, note=note)
    return Client(address, security=security, timeout=f"{CONNECT_TIMEOUT:g}s")


def invalid_bakes(entries: list) -> list:
    """The invalid bakes of a job's (name, spec or JobError) entries, as outcomes: a farm run checks them before
    it reaches a machine, as a one-machine run does before any work."""
    return [JobOutcome(n, "invalid", str(s)) for n, s in entries if isinstance(s, JobError)]


def run_farm(job: str, client, force: bool = False, only: list | None = None, brick_voxels: int | None = None,
             retries: int = 2, progress=None, log=None, status=None, precision: str = "fp32") -> list:
    """Run a job file's bakes on ``client``'s cluster -> list of :class:`backend.jobs.JobOutcome` (one per bake).

    ``progress(fraction)`` (the core's contract) and ``status(done, total, bytes_moved, eta_seconds)`` after
    every finished task.  ``precision``: the neural denoiser's on every worker (see backend.neural.precision).
    Invalid bakes fail the
    job before anything is sent (as one-machine runs do).  A failed task fails its output, named in the
    outcome; every other output is still written.
    """
    from distributed import as_completed

    from omninoise import export

    job = os.path.abspath(job)
    entries = select_bakes(load_job(job), only)
    bad = invalid_bakes(entries)
    if bad:
        return bad
    manifest = read_manifest(job)
    tag = f"farm-{uuid.uuid4().hex[:12]}"     # this run's temporaries: the only ones it removes
    tasks, skipped, volumes = plan(entries, force, brick_voxels or brick_voxels_for(client), manifest)
    specs = dict(entries)
    futures = {}
    for t in tasks:
        if t.brick is None:
            fut = client.submit(run_file, job, t.bake, t.frame, tag, precision, retries=retries, pure=False)
        else:
            fut = client.submit(run_brick, job, t.bake, t.frame, t.brick[0], t.brick[1], tag, precision,
                                retries=retries, pure=False)
        futures[fut] = t
    writers, bricks_done, failed, written = {}, {}, {}, {}
    done, moved, t0 = 0, 0, time.perf_counter()
    for fut in as_completed(list(futures)):
        t = futures[fut]
        done += 1
        spec = specs[t.bake]
        try:
            res = fut.result()
        except Exception as exc:  # noqa: BLE001  (the task's own error, after Dask's retries)
            failed.setdefault(t.path, f"{os.path.basename(t.path)}: {type(exc).__name__}: {exc}")
            writers.pop(t.path, None)
            res = None
        if res is not None and t.brick is None:
            rec = file_record(t.path) if os.path.isfile(t.path) else None
            if rec is None or rec["bytes"] != res["bytes"] or rec["sha256"] != res["sha256"]:
                failed.setdefault(t.path, f"{os.path.basename(t.path)}: the file does not match what the worker "
                                          "reported (shared storage?)")
            else:
                moved += rec["bytes"]
                written[t.path] = dict(rec, bake=t.bake, frame=t.frame, key=spec.key(t.frame))
            export.remove_partials(t.path, tag)
        elif res is not None and t.path not in failed:
            w = writers.get(t.path)
            if w is None:
                meta = {KEY_NAME: spec.key(t.frame), "omninoise_source": spec.source.kind,
                        "omninoise_bake": spec.name}
                w = writers[t.path] = export.VolumeWriter(spec.grid.voxel, spec.grid.first, volume_grids(spec),
                                                          meta, half=spec.half)
            for name, slab in res.items():
                w.add(name, t.brick[0], slab)
                moved += slab.nbytes
            bricks_done[t.path] = bricks_done.get(t.path, 0) + 1
            if bricks_done[t.path] == volumes[t.path][2]:
                os.makedirs(os.path.dirname(os.path.abspath(t.path)), exist_ok=True)
                with export.tagged(tag):
                    writers.pop(t.path).write(t.path)
                export.remove_partials(t.path, tag)
                written[t.path] = dict(file_record(t.path), bake=t.bake, frame=t.frame, key=spec.key(t.frame))
        if progress is not None:
            progress(done / len(tasks))
        if status is not None:
            rate = (time.perf_counter() - t0) / done
            status(done, len(tasks), moved, rate * (len(tasks) - done))
    for path in failed:
        export.remove_partials(path, tag)
    manifest.update({os.path.abspath(p): r for p, r in written.items()})
    for p in failed:
        manifest.pop(os.path.abspath(p), None)
    export.write_json(manifest_path(job), dict(job=job, outputs=manifest))
    outcomes = []
    for name, spec in entries:
        paths = [frame_path(spec.output, f) for f in spec.frame_list()]
        bad_here = [failed[p] for p in paths if p in failed]
        n_written = sum(p in written for p in paths)
        n_skipped = sum(p in skipped for p in paths)
        if bad_here:
            outcomes.append(JobOutcome(name, "failed", f"bake {name!r}: {len(bad_here)} of {len(paths)} outputs "
                                                       f"failed: {'; '.join(bad_here[:3])}"))
        else:
            outcomes.append(JobOutcome(name, "baked" if n_written else "up to date",
                                       f"{n_written} written, {n_skipped} up to date"))
        if log is not None:
            log(outcomes[-1].message)
    return outcomes
