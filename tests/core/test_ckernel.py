"""The C row and point kernels (backend/wavenoise/rows.c) against the numba kernels, their reference."""
import os
import shutil
import sys

import numpy as np
import pytest

from omninoise.backend import Spectrum, WaveSettings, compile_noise, evaluate_grid
from omninoise.backend.wavenoise import ckernel, fast

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HAS_CC = any(shutil.which(c) for c in (os.environ.get("CC") or "cc", "gcc", "clang"))


@pytest.fixture(scope="module", autouse=True)
def built():
    """The kernel as make setup builds it; built here if a compiler exists but the library does not."""
    if not ckernel.available():
        if not HAS_CC:
            pytest.skip("no C compiler: the engine runs its numba kernel")
        sys.path.insert(0, os.path.join(ROOT, "tools"))
        import build_kernel
        assert build_kernel.build(), "the C kernel failed to build"
        ckernel._lib = None
    assert ckernel.available()


def _case(dim, extent, directions=12, speed=0.0, seed=5, spectrum=("bandpass", 3, 9), table_size=None):
    extra = {} if table_size is None else {"table_size": table_size}
    noise = compile_noise(WaveSettings(dim=dim, spectrum=Spectrum(*spectrum), directions=directions, seed=seed,
                                       speed=speed, **extra))
    return noise


def _rows(noise, xs, others, time=0.4, mode="c", imag=True, threads=None):
    """One set of rows by the C kernel (mode c / scalar) or the numba reference (mode numba)."""
    lo = np.concatenate([[xs.min()], others.min(0)]).astype(np.float32)
    hi = np.concatenate([[xs.max()], others.max(0)]).astype(np.float32)
    plan = fast.grid_plan(noise, lo, hi, time)
    re = np.empty((len(others), len(xs)), np.float32)
    im = np.empty_like(re) if imag else None
    if mode == "numba":
        plan.ctables = None
        plan.rows(xs, others, re, im)
    else:
        saved = ckernel._threads
        if threads:
            ckernel._threads = lambda: threads
        try:
            ckernel.rows(xs, others, noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, plan.nmin, plan.slpos,
                         plan.omega, plan.zeta, plan.ctables, np.float32(1.0 / noise.table.period), plan.shift,
                         re, im, use_vector=(mode == "c"))
        finally:
            ckernel._threads = saved
    return re, im


def _row_set(dim, nx, x0, x1, rows=23, spread=5.0, seed=0):
    xs = np.linspace(x0, x1, nx).astype(np.float32)
    others = np.random.default_rng(seed).uniform(-spread, spread, (rows, dim - 1)).astype(np.float32)
    return xs, others


needs_numba = pytest.mark.skipif(not fast.available(), reason="numba (the reference) not installed")


@needs_numba
@pytest.mark.parametrize("dim,nx,x0,x1,speed", [
    (2, 203, -1.3, 3.7, 0.0),      # slices of 38 samples and more: the walk, rows not a multiple of 8
    (3, 128, 0.0, 4.0, 0.0),       # the bench's 3D row
    (3, 101, 0.0, 6.5, 0.0),       # slices of 15 to 50 samples: blocks and walk in one row set
    (3, 37, 10.0, 11.0, 0.6),      # animated, far from the origin
    (4, 16, -2.0, 2.0, 0.0),
    (2, 1024, 0.0, 0.5, 0.0),      # long slices: the segment walk
    (2, 300, -40.0, 40.0, 0.0),    # dozens of slices per row: records gathered, not permuted
    (3, 1, 0.3, 0.3, 0.0),         # one sample per row
    (2, 7, 0.0, 0.01, 0.0),        # fewer samples than one vector
])
@pytest.mark.long
def test_c_kernel_equals_numba(dim, nx, x0, x1, speed):
    noise = _case(dim, x1 - x0, speed=speed)
    xs, others = _row_set(dim, nx, x0, x1)
    ref_re, ref_im = _rows(noise, xs, others, mode="numba")
    for mode in ("c", "scalar"):
        re, im = _rows(noise, xs, others, mode=mode)
        for a, b in ((re, ref_re), (im, ref_im)):
            d = np.abs(a - b).max()
            # the segment walk and the scalar loops are numba's operations one for one; the blocks fuse
            # the weights' multiply-adds (about 1 ulp); a wrong slice, weight or texel would differ by O(0.1)
            assert d <= (0.0 if mode == "scalar" else 2e-6), (mode, d)
    assert ref_re.std() > 0.1  # a real signal was compared
    real_only, _ = _rows(noise, xs, others, mode="c", imag=False)
    assert np.array_equal(real_only, _rows(noise, xs, others, mode="c")[0])


@needs_numba
@pytest.mark.parametrize("table_size", [1000, 4096, 640])
def test_table_sizes_wrap_alike(table_size):
    """The AVX2 loops wrap texel indices with an integer and where the table size is a power of two, with
    numba's float operations elsewhere: both against the reference, on short (blocks) and long (walk) slices."""
    for dim, nx, x0, x1 in ((3, 128, -3.0, 4.0), (2, 1024, 0.0, 0.5)):
        noise = _case(dim, x1 - x0, table_size=table_size)
        xs, others = _row_set(dim, nx, x0, x1, rows=17, spread=30.0)
        ref_re, ref_im = _rows(noise, xs, others, mode="numba")
        re, im = _rows(noise, xs, others)
        assert np.abs(re - ref_re).max() <= 2e-6 and np.abs(im - ref_im).max() <= 2e-6, table_size
        assert ref_re.std() > 0.1


@needs_numba
def test_axis_aligned_direction_and_threads():
    """A stratum whose slices do not change along the row (s_x = 0), and rows split over threads."""
    noise = _case(3, 4.0, directions=8, seed=2)
    noise.slice_dirs[0] = np.array([0.0, 0.6, 0.8], np.float32)  # p constant along x for stratum 0
    xs, others = _row_set(3, 77, 0.0, 4.0, rows=41)
    ref, _ = _rows(noise, xs, others, mode="numba")
    one, _ = _rows(noise, xs, others, threads=1)
    two, _ = _rows(noise, xs, others, threads=3)
    assert np.array_equal(one, two)
    assert np.abs(one - ref).max() <= 2e-6


def test_grid_without_numba_uses_the_c_kernel(monkeypatch):
    """Blender's Python has no numba: grids still get a plan, run by the C kernel, equal to numpy."""
    noise = _case(3, 3.0)
    monkeypatch.setattr(fast, "numba", None)
    plan = fast.grid_plan(noise, np.zeros(3, np.float32), np.full(3, 3.0, np.float32), 0.4)
    assert plan is not None and plan.ctables is not None
    a = evaluate_grid(noise, 20, 3.0, "real", 0.4)
    g = np.arange(20, dtype=np.float32) * np.float32(3.0 / 20)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    b = noise.evaluate(pts, 0.4, accelerate=False).real.reshape(a.shape)
    assert np.percentile(np.abs(a - b), 99) < 3e-4 and np.abs(a - b).max() < 1e-3


@pytest.mark.parametrize("dim,speed,time", [(2, 0.0, 0.0), (3, 0.0, 0.0), (3, 1.5, 0.7), (4, 0.0, 0.0)])
def test_point_kernel_gives_numba_bits(dim, speed, time, monkeypatch):
    """fast.evaluate without numba (as in Blender) runs the C point kernel: numba's bits, on 2 threads and on 1."""
    if not fast.numba:
        pytest.skip("numba is the reference")
    noise = _case(dim, 4.0, speed=speed, spectrum=("fractal", 1.0, 4.0))
    x = np.random.default_rng(dim).uniform(-6.0, 6.0, (20011, dim)).astype(np.float32)
    want = fast.evaluate(noise, x, time)
    monkeypatch.setattr(fast, "numba", False)
    assert fast.supports(noise)
    got = fast.evaluate(noise, x, time)
    monkeypatch.setattr(ckernel, "_threads", lambda: 1)
    one = fast.evaluate(noise, x, time)
    assert got.dtype == np.complex64 and np.array_equal(got.view(np.uint32), want.view(np.uint32))
    assert np.array_equal(one.view(np.uint32), want.view(np.uint32))
    re, im = np.empty(len(x), np.float32), np.empty(len(x), np.float32)     # the scalar build (CPUs without AVX2)
    ckernel.points(x, noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, *fast._slice_records(noise, x.min(0),
                   x.max(0)), fast._padded_table(noise), np.float32(1.0 / noise.table.period),
                   np.float32(noise.speed) * np.float32(time), re, im, use_vector=False)
    assert np.array_equal(re, want.real) and np.array_equal(im, want.imag)
    numpy = noise.evaluate(x, time, accelerate=False)
    assert np.abs(got - numpy).max() < 1e-5 and np.abs(got).max() > 0.1


def test_point_and_cell_kernels_refuse_bad_arrays():
    noise = _case(3, 2.0)
    x = np.zeros((8, 3), np.float32)
    rec = fast._slice_records(noise, x.min(0), x.max(0))
    table = fast._padded_table(noise)
    out = np.empty(8, np.float32)
    with pytest.raises(ValueError, match="C-contiguous"):
        ckernel.points(x.astype(np.float64), noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, *rec, table,
                       1.0, 0.0, out, out.copy())
    with pytest.raises(ValueError, match="shapes"):
        ckernel.points(x, noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, *rec, table, 1.0, 0.0,
                       np.empty(7, np.float32), out)
    f, w = np.full(8, 8.0, np.float32), np.zeros(8, np.int64)
    near, hashes = np.zeros((2, 3), np.float32), np.zeros((2, 1, 3), np.float32)
    with pytest.raises(ValueError, match="int64"):
        ckernel.cells(x, np.zeros(8, np.int32), near, hashes, 0, 0.9, f, f.copy(), w)
    with pytest.raises(ValueError, match="shapes"):
        ckernel.cells(x, np.zeros(8, np.int64), near, hashes[:1], 0, 0.9, f, f.copy(), w)


def test_switch_off_and_bad_arrays():
    noise = _case(2, 2.0)
    before = ckernel.set_enabled(False)
    try:
        plan = fast.grid_plan(noise, np.zeros(2, np.float32), np.full(2, 2.0, np.float32), 0.0)
        assert plan is None or plan.ctables is None  # numba's kernel (or numpy) runs
    finally:
        ckernel.set_enabled(before)
    plan = fast.grid_plan(noise, np.zeros(2, np.float32), np.full(2, 2.0, np.float32), 0.0)
    xs = np.linspace(0, 2, 16).astype(np.float32)
    others = np.zeros((4, 1), np.float32)
    out = np.empty((4, 32), np.float32)[:, ::2]  # not contiguous
    with pytest.raises(ValueError, match="C-contiguous"):
        ckernel.rows(xs, others, noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, plan.nmin, plan.slpos,
                     plan.omega, plan.zeta, plan.ctables, np.float32(1.0), plan.shift, out)
    with pytest.raises(ValueError, match="shapes"):
        ckernel.rows(xs[:5], others, noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, plan.nmin, plan.slpos,
                     plan.omega, plan.zeta, plan.ctables, np.float32(1.0), plan.shift, np.empty((4, 16), np.float32))


@pytest.mark.long
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the native kernel wheel is built on Linux")
def test_kernel_wheel_installs_and_loads(tmp_path):
    """The wheel make dist ships (here built with this machine's compiler): valid RECORD, and once installed
    the runtime finds its library where no local build exists (an installed extension)."""
    import base64
    import hashlib
    import subprocess
    import zipfile
    sys.path.insert(0, os.path.join(ROOT, "tools"))
    import build_kernel
    wheel = build_kernel.kernel_wheel("linux-x64", str(tmp_path / "w"), native=True)
    assert wheel and wheel.endswith("-py3-none-manylinux_2_17_x86_64.whl")
    z = zipfile.ZipFile(wheel)
    record = z.read([n for n in z.namelist() if n.endswith("RECORD")][0]).decode().splitlines()
    for line in record:
        name, digest, size = line.rsplit(",", 2)
        if digest:
            data = z.read(name)
            want = "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            assert digest == want and int(size) == len(data), name
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-index", "--target",
                        str(target), wheel], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    code = ("import sys; from backend.wavenoise import ckernel; "
            "ckernel.local_path = lambda: '/nonexistent/_omni_rows.so'; "
            "print(ckernel.library_path()); print(ckernel.available())")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(target), ROOT]))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=str(tmp_path))
    path, ok = r.stdout.split()
    assert path.startswith(str(target)) and ok == "True", r.stdout + r.stderr


@needs_numba
@pytest.mark.parametrize("dim,nx,x0,x1", [(3, 128, 0.0, 4.0), (2, 1024, 0.0, 0.5), (2, 300, -40.0, 40.0)])
def test_fetch_modes_give_the_same_bits(monkeypatch, dim, nx, x0, x1):
    """The AVX2 loops read the table through register windows or through gathers; both read the same texels."""
    if not ckernel.vector():
        pytest.skip("no AVX2 on this CPU: the scalar loops run")
    noise = _case(dim, x1 - x0)
    xs, others = _row_set(dim, nx, x0, x1, rows=40)
    out = {}
    for mode in ckernel.FETCH_MODES:
        monkeypatch.setattr(ckernel, "_fetch", mode)
        out[mode] = _rows(noise, xs, others, threads=2)
    assert np.array_equal(out["window"][0], out["gather"][0]) and np.array_equal(out["window"][1], out["gather"][1])
    assert out["window"][0].std() > 0.1


def test_first_large_call_picks_a_fetch_mode(monkeypatch):
    """A process's first call with enough samples times both read forms on its own rows and keeps one; the rows
    it computed while timing are the same as those of a call that did not time (same bits)."""
    if not ckernel.vector():
        pytest.skip("no AVX2 on this CPU: the scalar loops run")
    noise = _case(3, 4.0)
    xs, others = _row_set(3, 128, 0.0, 4.0, rows=ckernel.CALIBRATE_SAMPLES // 128 + 16)
    monkeypatch.setattr(ckernel, "_fetch", None)
    timed = _rows(noise, xs, others, threads=2)
    assert ckernel.fetch_mode() in ckernel.FETCH_MODES
    monkeypatch.setattr(ckernel, "_fetch", "window")
    assert np.array_equal(timed[0], _rows(noise, xs, others, threads=2)[0])
    monkeypatch.setattr(ckernel, "_fetch", None)  # too small to time: the default form, nothing chosen
    small = _rows(noise, xs[:8], others[:3], threads=2)
    assert ckernel.fetch_mode() is None and np.isfinite(small[0]).all()


def test_bad_fetch_mode_is_named(monkeypatch, capsys, tmp_path):
    """A setting error (exit 2, one line naming the variable), not an internal error."""
    from omninoise.backend.errors import SettingError
    from omninoise.cli.main import main

    monkeypatch.setattr(ckernel, "_fetch", "fast")
    with pytest.raises(SettingError, match="OMNINOISE_FETCH: must be one of window, gather, got 'fast'"):
        ckernel.fetch_mode()
    if ckernel.available():
        assert main(["wave", "--size", "256", "--quiet", "-o", str(tmp_path / "w.npy")]) == 2
        assert capsys.readouterr().err.strip() == ("omninoise wave: error: OMNINOISE_FETCH: must be one of window, "
                                                   "gather, got 'fast'")
        assert not (tmp_path / "w.npy").exists()
