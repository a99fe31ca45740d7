"""``omninoise bake``: every bake of a TOML job file, here or on a Dask farm (:mod:`.farm`)."""
from __future__ import annotations

import argparse
import os
import sys

from omninoise.backend import limits
from omninoise.backend.errors import SettingError
from omninoise.backend.neural.precision import PRECISIONS

from .common import Bar, add_command, set_threads, shown, split_address

__all__ = ["add_parser", "run"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    b = add_command(sub, "bake", "run the bakes of a TOML job file",
                    "Run every bake of a job file (TOML): wave, neural and solid sources into .vdb, .exr, .png and .npy "
                    "files, numbered sequences included. Outputs that are up to date are skipped. Every bake is checked "
                    "before any runs. The job-file reference is in docs/guide/jobs.md.",
                    """omninoise bake job.toml
omninoise bake job.toml --only clouds --force
omninoise bake job.toml --dry-run
omninoise bake job.toml --workers 2""")
    b.add_argument("job", help="job file (.toml)")
    b.add_argument("--only", action="append", metavar="NAME", help="bake only these (repeatable)")
    b.add_argument("--force", action="store_true", help="re-bake outputs that are up to date")
    b.add_argument("--keep-going", action="store_true", help="after a failed bake, carry on with the others")
    b.add_argument("--dry-run", action="store_true", help="check the job and list what would be baked")
    b.add_argument("--threads", type=int, default=0, help="CPU threads for the neural models (0: all cores)")
    b.add_argument("--precision", default="fp32", choices=PRECISIONS,
                   help="neural noise arithmetic (int8: a faster draft on CPUs with int8 dot products)")
    b.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    farm = b.add_argument_group("farm (Dask; pip install 'omninoise[farm]')")
    farm.add_argument("--workers", type=int, metavar="N",
                      help="bake on a local cluster of N worker processes (at most one per CPU)")
    farm.add_argument("--cluster", metavar="ADDRESS", help="bake on a running Dask scheduler (tcp:// or tls://)")
    farm.add_argument("--retries", type=int, default=2, help="runs of a failed task after the first")
    farm.add_argument("--brick-voxels", type=int, help="voxels per brick of a large volume (default: from the "
                                                       "workers' memory)")
    farm.add_argument("--tls-ca-file", help="tls://: the CA certificate")
    farm.add_argument("--tls-cert", help="tls://: this client's certificate")
    farm.add_argument("--tls-key", help="tls://: this client's private key")
    return b


TLS_FLAGS = (("--tls-ca-file", "tls_ca_file"), ("--tls-cert", "tls_cert"), ("--tls-key", "tls_key"))


def check_cluster(a: argparse.Namespace) -> None:
    """Refuse, before any work, a ``--cluster`` that is not a scheduler's address (``tcp://HOST:PORT``,
    ``tls://HOST:PORT`` or ``HOST:PORT``, which is tcp), a tls:// address without its three certificate files (each
    an existing file), and those files beside an address that is not tls://."""
    scheme, host, port = split_address(a.cluster)
    if scheme not in ("tcp", "tls") or not host.strip("[]") or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise SettingError("--cluster", "expected a Dask scheduler's address, tcp://HOST:PORT or tls://HOST:PORT, "
                                        f"got {a.cluster!r}")
    for flag, key in TLS_FLAGS:
        path = getattr(a, key)
        if scheme != "tls" and path:
            raise SettingError(flag, f"applies to a tls:// scheduler; {a.cluster} is not encrypted")
        if scheme == "tls" and not path:
            raise SettingError(flag, "a tls:// scheduler needs --tls-ca-file, --tls-cert and --tls-key")
        if path and not os.path.isfile(path):
            raise SettingError(flag, f"no such file: {path}")


def check_precision(a: argparse.Namespace) -> None:
    """Refuse ``--precision int8`` for a job (or the bakes ``--only`` names) with no neural noise bake, every bake
    valid: int8 is the denoiser's arithmetic, and the files would be those of fp32. (An invalid bake is reported by
    the job's own check.)"""
    from omninoise.backend.jobs import JobError, load_job, select_bakes

    if a.precision == "fp32":
        return
    entries = select_bakes(load_job(a.job), a.only)
    if not any(isinstance(s, JobError) or getattr(s.source, "kind", None) == "neural" for _, s in entries):
        raise SettingError("--precision", "sets the neural noise's arithmetic, and no bake of the job is neural "
                                          "noise: it would change nothing")


def run(a: argparse.Namespace) -> int:
    from omninoise.backend.jobs import JobError, load_job, run_job, select_bakes

    farm = a.workers is not None or a.cluster is not None
    for flag, given in (("--retries", a.retries != 2), ("--brick-voxels", a.brick_voxels is not None),
                        *((f, getattr(a, key)) for f, key in TLS_FLAGS)):
        if given and not farm:
            raise SettingError(flag, "applies to a farm bake: give --workers N or --cluster ADDRESS too")
    if a.cluster is not None:
        check_cluster(a)
    check_precision(a)
    if a.dry_run:       # what the run would do: the bakes --only names, up-to-date ones baked again with --force
        entries = select_bakes(load_job(a.job), a.only)
        bad = [s for _, s in entries if isinstance(s, JobError)]
        for name, spec in entries:
            if isinstance(spec, JobError):
                print(f"  invalid  {shown(spec)}")
            else:
                frames = spec.frame_list()
                fresh = 0 if a.force else sum(spec.is_up_to_date(f) for f in frames)
                state = "up to date" if fresh == len(frames) else "to bake"
                print(f"  {state:10s} {shown(name)}: {list(spec.grid.resolution)} -> {shown(spec.output)}"
                      + (f" ({len(frames)} frames, {fresh} up to date)" if spec.frames else ""))
        if bad:
            print(f"omninoise bake: error: {len(bad)} of {len(entries)} bakes are invalid (listed above)",
                  file=sys.stderr)
            return 2
        return 0
    set_threads(a.threads, a.precision)
    if farm:
        return _on_farm(a)
    now = {}      # the bake in progress: one bar per bake

    def on_bake(name, i, count):
        now.update(bar=Bar(a.quiet, f"[{i + 1}/{count}] {name} "), i=i, count=count)

    def progress(frac):   # the job's fraction -> this bake's
        now["bar"](min(1.0, max(0.0, frac * now["count"] - now["i"])))

    outcomes = run_job(a.job, keep_going=a.keep_going, force=a.force, only=a.only, progress=progress,
                       on_bake=on_bake)
    failed = [o for o in outcomes if o.status != "baked" and o.status != "up to date"]
    for o in outcomes:
        if o.status in ("baked", "up to date") and not a.quiet:
            print(f"omninoise bake: {shown(o.name)}: {o.status} ({shown(o.message)})", file=sys.stderr)
    for o in failed:
        print(f"omninoise bake: {'cancelled' if o.status == 'cancelled' else 'error'}: {shown(o.message)}",
              file=sys.stderr)
    # exit status as documented: 2 bad input, 130 interrupted, 1 a failure while running
    if any(o.status == "invalid" for o in failed):
        return 2
    if any(o.status == "cancelled" for o in failed):
        return 130
    return 1 if failed else 0


def _farm_outcomes(a: argparse.Namespace, farm) -> list:
    """The job's outcomes from a run on the cluster ``a`` names (``farm`` is cli/farm.py)."""
    try:
        note = None if a.quiet else (lambda text: print(f"omninoise bake: {text}", file=sys.stderr))
        client = farm.local_client(a.workers) if a.workers else farm.remote_client(a.cluster, a.tls_ca_file,
                                                                                   a.tls_cert, a.tls_key, note)
    except ImportError as exc:
        raise SettingError("--workers" if a.workers else "--cluster",
                           f"needs Dask distributed ({exc}); pip install 'dask[distributed]'") from None
    except OSError as exc:
        raise SettingError("--cluster", f"cannot reach the scheduler {a.cluster}: {exc}") from None
    try:
        if not a.quiet and client.dashboard_link:
            print(f"omninoise bake: Dask dashboard {client.dashboard_link}", file=sys.stderr)

        bar = Bar(a.quiet)

        def status(done, total, moved, eta):
            bar(done / max(total, 1), f"  {done}/{total} tasks, {moved / 2 ** 20:.1f} MiB, ETA {eta:.0f} s   ")

        return farm.run_farm(a.job, client, force=a.force, only=a.only, brick_voxels=a.brick_voxels,
                             retries=a.retries, status=status, precision=a.precision)
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None:
            cluster.close()


MAX_RETRIES = 100     #: the most runs of a failed farm task after its first


def _on_farm(a: argparse.Namespace) -> int:
    """``bake --workers N`` / ``--cluster ADDRESS``: the job on Dask (cli/farm.py); exit codes as locally."""
    from omninoise.backend.jobs import JobError, load_job, select_bakes

    if a.workers is not None and a.cluster:
        raise SettingError("--workers", "choose one of --workers (a local cluster) and --cluster (a scheduler)")
    if a.workers is not None and not 1 <= a.workers <= 512:
        raise SettingError("--workers", f"must be 1 to 512, got {a.workers}")
    cpus = limits.cpus()
    if a.workers is not None and a.workers > cpus:     # they share its CPUs: 32 on 2 took 10 times as long
        raise SettingError("--workers", f"{a.workers} workers is more than the {cpus} CPUs this machine has, which a "
                                        f"local cluster's workers share; ask for at most {cpus}")
    if not 0 <= a.retries <= MAX_RETRIES:       # a task that always fails would run that many times
        raise SettingError("--retries", f"must be 0 to {MAX_RETRIES}, got {a.retries}")
    if a.brick_voxels is not None and a.brick_voxels < 1:
        raise SettingError("--brick-voxels", f"must be >= 1, got {a.brick_voxels}")
    if not os.path.isfile(a.job):
        raise JobError(f"job file not found: {a.job}")
    try:
        from . import farm
    except ImportError as exc:
        raise SettingError("--workers" if a.workers else "--cluster",
                           f"needs Dask ({exc}); pip install 'dask[distributed]' or the farm extra") from None
    # the job's bakes are checked before a cluster is started or a scheduler reached (which may take 30 s)
    outcomes = farm.invalid_bakes(select_bakes(load_job(a.job), a.only)) or _farm_outcomes(a, farm)
    for o in outcomes:
        if o.status in ("baked", "up to date") and not a.quiet:
            print(f"omninoise bake: {shown(o.name)}: {o.status} ({shown(o.message)})", file=sys.stderr)
    bad = [o for o in outcomes if o.status not in ("baked", "up to date")]
    for o in bad:
        print(f"omninoise bake: error: {shown(o.message)}", file=sys.stderr)
    if any(o.status == "invalid" for o in bad):
        return 2
    return 1 if bad else 0
