"""Job files on a Dask cluster, on a local cluster of 2 worker processes over loopback: the same
files as a one-machine bake (images, a sequence, a bricked volume, a neural map), a worker killed mid-task,
resume, and a failing output that leaves the others written."""
import os
import shutil
import subprocess

import numpy as np
import pytest

pytest.importorskip("distributed")

from omninoise import export  # noqa: E402
from omninoise.cli import farm  # noqa: E402
from omninoise.cli.main import main  # noqa: E402
from omninoise.backend.jobs import run_job  # noqa: E402
from omninoise.export import read_volume  # noqa: E402
from omninoise.export.images import decode  # noqa: E402
from conftest import needs_openvdb  # noqa: E402

JOB = """
[[bake]]
name = "image"
output = "out/img.exr"
resolution = [32, 24]
[bake.source]
dim = 2
directions = 4
seed = 3

[[bake]]
name = "seq"
output = "out/seq_##.png"
resolution = [16, 16]
frames = [1, 3]
transfer = "marble"
[bake.source]
dim = 2
speed = 0.5
directions = 4

[[bake]]
name = "cloud"
output = "out/cloud.vdb"
resolution = [20, 18, 17]
bounds = [[0, 0, 0], [2, 2, 2]]
transfer = "fire"
[bake.source]
dim = 3
directions = 4
seed = 5

[[bake]]
name = "raw"
output = "out/raw.npy"
resolution = [8, 8, 8]
[bake.source]
dim = 3
directions = 2

[[bake]]
name = "neural"
output = "out/n.npy"
resolution = [16, 16]
[bake.source]
kind = "neural"
noise = "perlin"
steps = 2
"""
OUTPUTS = ["img.exr", "seq_01.png", "seq_02.png", "seq_03.png", "cloud.vdb", "raw.npy", "n.npy"]
BRICK = 20 * 18 * 5  # the 17-slice volume goes as 4 bricks


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    """One local cluster for the module; its workers inherit the crash hook's variable (armed by one test)."""
    marker = tmp_path_factory.mktemp("crash") / "crash-once"
    old = os.environ.get(farm.CRASH_ENV)
    os.environ[farm.CRASH_ENV] = str(marker)
    c = farm.local_client(2)
    try:
        yield c, marker
    finally:
        c.close()
        c.cluster.close()
        if old is None:
            os.environ.pop(farm.CRASH_ENV, None)
        else:
            os.environ[farm.CRASH_ENV] = old


def job_in(folder, text=JOB) -> str:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "job.toml").write_text(text)
    return str(folder / "job.toml")


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The one-machine bake of the job."""
    job = job_in(tmp_path_factory.mktemp("local"))
    assert {o.status for o in run_job(job)} == {"baked"}
    return os.path.dirname(job)


def assert_same_outputs(a: str, b: str, others: tuple = ()) -> None:
    for name in OUTPUTS:
        pa, pb = os.path.join(a, "out", name), os.path.join(b, "out", name)
        if name.endswith(".npy"):
            np.testing.assert_array_equal(np.load(pa), np.load(pb), err_msg=name)
        elif name.endswith(".vdb"):
            from omninoise.export.vdb import openvdb_module

            vdb = openvdb_module()
            for grid, shape in (("density", (17, 18, 20)), ("color", (17, 18, 20, 3)), ("temperature", (17, 18, 20))):
                np.testing.assert_array_equal(read_volume(pa, grid, shape[:3]), read_volume(pb, grid, shape[:3]),
                                              err_msg=f"{name}:{grid}")
                assert vdb.read(pa, grid).activeVoxelCount() == vdb.read(pb, grid).activeVoxelCount()
        else:
            np.testing.assert_array_equal(decode(pa), decode(pb), err_msg=name)
    left = [n for n in os.listdir(os.path.join(b, "out")) if n.startswith(".omninoise-")]
    assert sorted(left) == sorted(others), left  # no partial file of the farm's; another process's stay


@pytest.mark.long
@needs_openvdb
def test_a_mixed_job_on_two_workers_equals_the_one_machine_bake(client, reference, tmp_path):
    c, _ = client
    job = job_in(tmp_path)
    seen = []
    fractions = []
    outcomes = farm.run_farm(job, c, brick_voxels=BRICK, progress=fractions.append, status=lambda *p: seen.append(p))
    assert [(o.name, o.status) for o in outcomes] == [(n, "baked") for n in ("image", "seq", "cloud", "raw", "neural")]
    assert len(seen) == 3 + 3 + 4 and seen[-1][0] == seen[-1][1] == 10 and seen[-1][2] > 0  # 6 files + 4 bricks
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and len(fractions) == 10
    assert_same_outputs(reference, str(tmp_path))
    # resume: everything is up to date (the .npy outputs through the manifest), --force redoes it all
    assert {o.status for o in farm.run_farm(job, c, brick_voxels=BRICK)} == {"up to date"}
    np.save(tmp_path / "out" / "raw.npy", np.zeros((8, 8, 8), np.float32))  # changed behind the manifest's back
    again = {o.name: o.status for o in farm.run_farm(job, c, brick_voxels=BRICK)}
    assert again["raw"] == "baked" and again["image"] == "up to date"
    assert {o.status for o in farm.run_farm(job, c, brick_voxels=BRICK, force=True)} == {"baked"}
    assert_same_outputs(reference, str(tmp_path))


@needs_openvdb
def test_a_worker_killed_mid_task_changes_nothing(client, reference, tmp_path):
    """The first task to run kills its worker after leaving half a file; Dask runs the task again on a live
    worker, and the outputs equal a clean run with no partial file left."""
    c, marker = client
    marker.write_text("armed")
    job = job_in(tmp_path)
    # another process writing the same files meanwhile: its temporaries are not the farm's to remove
    (tmp_path / "out").mkdir()
    others = tuple(export.partial_prefix(str(tmp_path / "out" / n)) + "x1y2z3" + os.path.splitext(n)[1]
                   for n in ("raw.npy", "cloud.vdb", "seq_02.png"))
    for n in others:
        (tmp_path / "out" / n).write_bytes(b"another writer's half file")
    outcomes = farm.run_farm(job, c, brick_voxels=BRICK)
    assert not marker.exists()  # a worker did die
    assert {o.status for o in outcomes} == {"baked"}
    assert_same_outputs(reference, str(tmp_path), others)


def test_a_failing_output_is_named_and_the_others_are_written(client, tmp_path):
    c, _ = client
    (tmp_path / "blocked").write_text("a file where the bake wants a folder")
    job = job_in(tmp_path, """
[[bake]]
name = "good"
output = "out/good.npy"
resolution = [8, 8]
[bake.source]
dim = 2
directions = 2

[[bake]]
name = "bad"
output = "blocked/x.npy"
resolution = [8, 8]
[bake.source]
dim = 2
directions = 2
""")
    outcomes = {o.name: o for o in farm.run_farm(job, c, retries=0)}
    assert outcomes["good"].status == "baked" and (tmp_path / "out" / "good.npy").is_file()
    assert outcomes["bad"].status == "failed" and "x.npy" in outcomes["bad"].message


def test_the_cli_runs_a_job_on_a_local_cluster(tmp_path, capsys):
    job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0])  # the image bake alone
    assert main(["bake", job, "--workers", "1", "--quiet"]) == 0
    assert (tmp_path / "out" / "img.exr").is_file()
    assert main(["bake", job, "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err
    assert main(["bake", job, "--workers", "1", "--cluster", "tcp://127.0.0.1:1"]) == 2


def test_a_local_cluster_has_at_most_a_worker_per_cpu(tmp_path, capsys, monkeypatch):
    """A local cluster's workers share the machine's CPUs: 32 workers on 2 CPUs baked 16 frames in 17.3 s against
    1.8 s with 2, and 512 (the bound before) would have started 512 processes of about 140 MB each. More workers
    than CPUs are refused before any work, naming the count."""
    from omninoise.backend import limits

    monkeypatch.setattr(limits, "cpus", lambda: 2)
    job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0])
    assert main(["bake", job, "--workers", "3", "--quiet"]) == 2
    assert capsys.readouterr().err.strip() == ("omninoise bake: error: --workers: 3 workers is more than the 2 CPUs "
                                               "this machine has, which a local cluster's workers share; ask for at "
                                               "most 2")
    assert not (tmp_path / "out" / "img.exr").exists()
    assert main(["bake", job, "--workers", "2", "--quiet"]) == 0 and (tmp_path / "out" / "img.exr").is_file()


@pytest.mark.parametrize("flags, message", [
    (["--workers", "513"], "--workers: must be 1 to 512, got 513"),
    (["--workers", "1", "--retries", "101"], "--retries: must be 0 to 100, got 101"),
    (["--workers", "1", "--retries", "-1"], "--retries: must be 0 to 100, got -1"),
    (["--workers", "1", "--brick-voxels", "0"], "--brick-voxels: must be >= 1, got 0"),
    (["--cluster", "farmhead"], "--cluster: expected a Dask scheduler's address, tcp://HOST:PORT or tls://HOST:PORT, "
                                "got 'farmhead'"),
    (["--cluster", "tcp://farmhead"], "--cluster: expected a Dask scheduler's address"),
    (["--cluster", "farmhead:99999"], "--cluster: expected a Dask scheduler's address"),
    (["--cluster", ""], "--cluster: expected a Dask scheduler's address, tcp://HOST:PORT or tls://HOST:PORT, got ''"),
    (["--cluster", "http://farmhead:8786"], "--cluster: expected a Dask scheduler's address"),
    (["--cluster", "tls://farmhead:8786", "--tls-ca-file", "{job}", "--tls-cert", "{job}"],
     "--tls-key: a tls:// scheduler needs --tls-ca-file, --tls-cert and --tls-key"),
    (["--cluster", "tls://farmhead:8786", "--tls-ca-file", "{job}", "--tls-cert", "/no/cert.pem", "--tls-key", "{job}"],
     "--tls-cert: no such file: /no/cert.pem"),
    (["--cluster", "tcp://farmhead:8786", "--tls-key", "{job}"],
     "--tls-key: applies to a tls:// scheduler; tcp://farmhead:8786 is not encrypted"),
])
def test_a_cluster_that_is_no_scheduler_address_is_refused_before_any_work(tmp_path, capsys, flags, message):
    job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0])
    assert main(["bake", job, "--quiet", *(f.format(job=job) for f in flags)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"omninoise bake: error: {message}") and "\n" not in err, err
    assert not (tmp_path / "out" / "img.exr").exists()


def test_a_farm_job_s_bad_bake_is_named_before_the_scheduler_is_reached(tmp_path, capsys):
    """No scheduler listens on port 1: the bad bake is what the error names, not the connection."""
    job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0].replace("resolution = [", "resolution = [0, "))
    assert main(["bake", job, "--quiet", "--cluster", "tcp://127.0.0.1:1"]) == 2
    err = capsys.readouterr().err
    assert "resolution" in err and "scheduler" not in err, err


@pytest.mark.parametrize("says, message", [
    (None, "it took the connection but sent nothing in 1 s, where a Dask scheduler greets at once"),
    (b"HTTP/1.0 400 Bad Request\r\nContent-Length: 0\r\n\r\n", "it answered, but not as a Dask scheduler does"),
])
def test_an_address_where_no_scheduler_greets_is_refused_in_one_line(tmp_path, capsys, monkeypatch, says, message):
    """A server that takes the connection and says nothing (a web server: a scheduler's dashboard) held Dask's
    connection for ever; one that says something else made it allocate the length its first bytes read as (an
    internal MemoryError). Both are named, the job left undone."""
    import socket
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if says:
                conn.sendall(says)

    threading.Thread(target=serve, daemon=True).start()
    monkeypatch.setattr(farm, "CONNECT_TIMEOUT", 1.0)
    try:
        job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0])
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        assert main(["bake", job, "--quiet", "--cluster", address]) == 2
    finally:
        server.close()
        for conn in held:
            conn.close()
    err = capsys.readouterr().err.strip()
    assert err == (f"omninoise bake: error: --cluster: cannot reach the scheduler {address}: {message} (a web page's "
                   "port, such as the dashboard's? a scheduler listens on port 8786 unless told otherwise)"), err
    assert not (tmp_path / "out" / "img.exr").exists()


def _free_port() -> int:
    import socket

    with socket.create_server(("127.0.0.1", 0)) as s:
        return s.getsockname()[1]


def test_a_port_where_nothing_listens_is_said_so_while_waiting_and_after(tmp_path, capsys, monkeypatch):
    """Dask tries a refused port again until its timeout (a scheduler may be starting), 30 s of silence that ended
    in 'Timed out trying to connect': the wait is said when it starts, and the error says nothing listens."""
    monkeypatch.setattr(farm, "CONNECT_TIMEOUT", 1.0)
    address = f"tcp://127.0.0.1:{_free_port()}"
    import socket

    assert farm.refused(address) and farm.refused(address.replace("tcp://", ""))
    with socket.create_server(("127.0.0.1", 0)) as listening:
        assert not farm.refused(f"tcp://127.0.0.1:{listening.getsockname()[1]}")
    job = job_in(tmp_path, JOB.split("[[bake]]\nname = \"seq\"")[0])
    assert main(["bake", job, "--cluster", address]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"omninoise bake: nothing listens at {address} yet; waiting up to 1 s for a scheduler to start",
        f"omninoise bake: error: --cluster: cannot reach the scheduler {address}: nothing listens on its port (the "
        "connection was refused for 1 s): start the scheduler (dask scheduler) or check the address"]
    assert main(["bake", job, "--cluster", address, "--quiet"]) == 2
    assert "waiting" not in capsys.readouterr().err
    assert not (tmp_path / "out" / "img.exr").exists()


def test_a_scheduler_that_starts_while_the_client_waits_is_reached(tmp_path):
    """The port refuses at first; the scheduler started meanwhile is reached within the wait, as Dask's own
    retries reach it."""
    import sys
    import threading

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    assert farm.refused(address)
    procs = []
    start = threading.Timer(0.5, lambda: procs.append(subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port),
         "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)))
    notes = []
    start.start()
    try:
        farm.probe_scheduler(address, note=notes.append)
        assert not farm.refused(address)
    finally:
        start.join()
        for p in procs:
            p.terminate()
            p.wait(10)
    assert notes == [f"nothing listens at {address} yet; waiting up to 30 s for a scheduler to start"]


def _certs(folder) -> tuple:
    """A throwaway CA and one certificate for 127.0.0.1 signed by it (openssl), as a farm's admin would make."""
    ca_key, ca, key, csr, cert = (str(folder / n) for n in ("ca.key", "ca.pem", "node.key", "node.csr", "node.pem"))
    run = lambda *a: subprocess.run(a, check=True, capture_output=True)  # noqa: E731
    run("openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=omninoise-test-ca",
        "-keyout", ca_key, "-out", ca)
    run("openssl", "req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1", "-keyout", key, "-out", csr)
    ext = folder / "ext.cnf"
    ext.write_text("subjectAltName = IP:127.0.0.1\n")
    run("openssl", "x509", "-req", "-in", csr, "-CA", ca, "-CAkey", ca_key, "-CAcreateserial", "-days", "1",
        "-extfile", str(ext), "-out", cert)
    return ca, cert, key


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl to make test certificates")
def test_a_tls_scheduler_is_reached_with_dask_security(tmp_path):
    """`--cluster tls://...` with --tls-ca-file/--tls-cert/--tls-key: the job runs over an encrypted
    connection; without the certificates the address is refused with a one-line error."""
    from distributed import LocalCluster
    from distributed.security import Security

    ca, cert, key = _certs(tmp_path)
    sec = Security(tls_ca_file=ca, tls_scheduler_cert=cert, tls_scheduler_key=key, tls_worker_cert=cert,
                   tls_worker_key=key, tls_client_cert=cert, tls_client_key=key, require_encryption=True)
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, protocol="tls://", host="127.0.0.1",
                           security=sec, dashboard_address=None)
    try:
        address = cluster.scheduler_address
        assert address.startswith("tls://127.0.0.1:")
        job = job_in(tmp_path / "job", JOB.split("[[bake]]\nname = \"seq\"")[0])
        assert main(["bake", job, "--cluster", address, "--tls-ca-file", ca, "--tls-cert", cert, "--tls-key", key,
                     "--quiet"]) == 0
        assert (tmp_path / "job" / "out" / "img.exr").is_file()
        with pytest.raises(Exception, match="tls-ca-file"):
            farm.remote_client(address)
    finally:
        cluster.close()
