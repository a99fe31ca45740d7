"""Neural noise in background Blender: swatches, layouts, painted maps, bake, errors, save/reload, panel draw."""
import os

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from conftest import Recorder  # noqa: E402
from omninoise.blender_addon import neural_ui, tasks  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from omninoise.export import images  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon():
    blender_addon.register()
    yield
    blender_addon.unregister()


@pytest.fixture
def scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    p = bpy.context.scene.omninoise_neural
    p.size, p.steps, p.seed = 32, 3, 5
    for _ in range(2):
        bpy.ops.omninoise.swatch_add()
    p.swatches[0].noise = "spots"
    p.swatches[1].noise = "damascus"
    return bpy.context.scene


def _pixels(name):
    ima = bpy.data.images[name]
    w, h = ima.size
    px = np.empty(w * h * 4, np.float32)
    ima.pixels.foreach_get(px)
    return np.flipud(px.reshape(h, w, 4)[..., 0])


def test_swatches_take_the_class_parameters(scene):
    sw = scene.omninoise_neural.swatches[0]
    params = neural_ui.model().class_params["spots"]["params"]
    assert sw.p0 == pytest.approx(0.5 * (params[0]["min"] + params[0]["max"]))
    name, values = sw.spec()
    assert name == "spots" and set(values) == {p["name"] for p in params}


@pytest.mark.parametrize("mode", ["SINGLE", "GRADIENT", "MAP"])
def test_bake_matches_the_runtime(scene, mode):
    p = scene.omninoise_neural
    p.mode = mode
    if mode == "MAP":
        bpy.ops.omninoise.blend_map_new()
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    got = _pixels(p.name)
    from omninoise.backend.neural.generate import generate

    ref = generate(neural_ui.model(), neural_ui.build_conditioning(p, 32), seed=5, steps=3)
    np.testing.assert_allclose(got, ref, atol=1e-6)
    assert bpy.data.images[p.name].colorspace_settings.name == "Non-Color"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    np.testing.assert_array_equal(_pixels(p.name), got)  # same seed and settings: same image


def test_int8_preference_bakes_with_the_int8_denoiser(scene, monkeypatch):
    """The Neural Precision preference reloads the model with the shipped int8 denoisers; the bake equals the
    runtime's int8 image and stays near the float32 one."""
    from omninoise.backend.neural.generate import generate

    p = scene.omninoise_neural
    assert neural_ui.model().precision == "fp32"  # the default
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    fp32 = _pixels(p.name)
    monkeypatch.setattr(neural_ui, "precision", lambda: "int8")
    m = neural_ui.model()
    assert m.precision == "int8" and m.denoiser_name(False) == "denoiser_int8.onnx"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    got = _pixels(p.name)
    np.testing.assert_allclose(got, generate(m, neural_ui.build_conditioning(p, 32), seed=5, steps=3), atol=1e-6)
    assert 0 < float(np.abs(got - fp32).mean()) < 0.15  # 3 steps at 32²: each step's quantization error shows
    monkeypatch.undo()
    assert neural_ui.model().precision == "fp32"


def test_painted_regions_carry_their_swatch(scene):
    """Left half spots, right half damascus: each side's conditioning is its swatch's."""
    p = scene.omninoise_neural
    bpy.ops.omninoise.blend_map_new()
    cond = neural_ui.build_conditioning(p, 32)
    from omninoise.backend.neural import conditioning as C

    m = neural_ui.model()
    np.testing.assert_allclose(cond[:, 0, 0], C.uniform(m, p.swatches[0].spec(), 1, 1)[:, 0, 0], atol=1e-5)
    np.testing.assert_allclose(cond[:, 0, -1], C.uniform(m, p.swatches[1].spec(), 1, 1)[:, 0, 0], atol=1e-5)


def test_clear_messages(scene, monkeypatch):
    p = scene.omninoise_neural
    p.mode = "CORNERS"
    with pytest.raises(RuntimeError, match="needs four swatches"):
        bpy.ops.omninoise.neural_bake()
    p.mode = "MAP"
    with pytest.raises(RuntimeError, match="pick or create a blend map"):
        bpy.ops.omninoise.neural_bake()
    img = bpy.data.images.new("odd", 16, 8)
    p.blend_map = img
    with pytest.raises(RuntimeError, match="the map is 16x8; it must be square"):
        bpy.ops.omninoise.neural_bake()
    gone = bpy.data.images.new("gone", 16, 16)
    gone.source, gone.filepath = "FILE", "//no_such_map.png"
    gone.reload()
    p.blend_map = gone
    with pytest.raises(RuntimeError, match="blend map: image 'gone' has no pixels"):
        bpy.ops.omninoise.neural_bake()
    hot = bpy.data.images.new("hot", 16, 16, float_buffer=True)     # a float render with a NaN pixel
    px = np.ones(16 * 16 * 4, np.float32)
    px[40] = np.nan
    hot.pixels.foreach_set(px)
    p.blend_map = hot
    with pytest.raises(RuntimeError, match="blend map: image 'hot' holds NaN or infinite values"):
        bpy.ops.omninoise.neural_bake()
    p.blend_map = bpy.data.images.new("wide", 64, 64)
    monkeypatch.setattr(images, "MAX_PIXELS", 64 * 63)     # read as a file is: one of 2^27 + 1 px is refused
    with pytest.raises(RuntimeError, match="blend map: image 'wide' is 64x64 px, more than the 4032 px an input "
                                           "may have"):
        bpy.ops.omninoise.neural_bake()
    monkeypatch.undo()
    tiles = bpy.data.images.new("tiles", 16, 16, tiled=True)
    tiles.tiles.new(tile_number=1002)
    p.blend_map = tiles
    with pytest.raises(RuntimeError, match="blend map: image 'tiles' is a UDIM tiled image; pick the image of one "
                                           "tile"):
        bpy.ops.omninoise.neural_bake()
    sq = bpy.data.images.new("green", 16, 16)
    sq.colorspace_settings.name = "Non-Color"
    sq.pixels.foreach_set(np.tile([0.0, 1.0, 0.0, 1.0], 256).astype(np.float32))
    p.blend_map = sq
    with pytest.raises(RuntimeError, match="matches no swatch colour"):
        bpy.ops.omninoise.neural_bake()
    p.mode, p.size = "SINGLE", 16384
    for op in (bpy.ops.omninoise.neural_bake, bpy.ops.omninoise.neural_bake_sequence):
        with pytest.raises(RuntimeError, match=r"size: a 16384 x 16384 neural image needs 64\.8 GiB, above the "):
            op()


def test_a_bake_saved_over_its_own_blend_map_file_is_refused_and_the_map_kept(scene, tmp_path):
    """A blend map painted and saved in the output folder under the bake's name would be written over."""
    p = scene.omninoise_neural
    p.folder, p.save, p.mode, p.size = str(tmp_path) + os.sep, "PNG", "MAP", 16
    painted = bpy.data.images.new("painted", 16, 16)
    painted.pixels.foreach_set(np.tile(list(p.swatches[0].color) + [1.0], 256).astype(np.float32))
    painted.filepath_raw, painted.file_format = str(tmp_path / (bpy.path.clean_name(p.name) + ".png")), "PNG"
    painted.save()
    p.blend_map = painted
    kept = (tmp_path / (bpy.path.clean_name(p.name) + ".png")).read_bytes()
    with pytest.raises(RuntimeError, match=r"name: .*\.png is the file the image 'painted' reads: write to another"):
        bpy.ops.omninoise.neural_bake()
    assert (tmp_path / (bpy.path.clean_name(p.name) + ".png")).read_bytes() == kept
    p.name = "Other"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"} and (tmp_path / "Other.png").is_file()

def test_settings_survive_save_and_reload(scene, tmp_path):
    p = scene.omninoise_neural
    p.swatches[1].p0 = 7.5
    p.seed, p.mode = 42, "GRADIENT"
    path = str(tmp_path / "n.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=path)
    q = bpy.context.scene.omninoise_neural
    assert [s.noise for s in q.swatches] == ["spots", "damascus"] and q.swatches[1].p0 == 7.5
    assert q.seed == 42 and q.mode == "GRADIENT"


def test_worker_bake_cancels_within_a_step(scene):
    p = scene.omninoise_neural
    p.size, p.steps = 64, 200
    op = neural_ui.OMNINOISE_OT_neural_bake
    task = op._start(type("Op", (), {"preview": False, "report": lambda *a: None})(), bpy.context, False)
    assert task.progressed.wait(120)  # the first step is done; no spinning
    task.cancel()
    tasks.wait(task)
    assert task.status == "cancelled" and task.progress < 0.5 and p.name not in bpy.data.images


def test_panel_draws(scene):
    log = []
    neural_ui.draw_neural_all(Recorder(log), bpy.context)
    names = [a for n, a, t in log if n == "prop"]
    assert {"noise", "color", "mode", "size", "steps", "seed", "tileable", "depth"} <= set(names)
    texts = [t for n, a, t in log if n == "prop" and a in ("p0", "p1")]
    active = scene.omninoise_neural.swatches[scene.omninoise_neural.active]
    want = [q["name"] for q in neural_ui.model().class_params[active.noise]["params"]]
    assert texts == [w.replace("_", " ").title() for w in want]  # sliders carry the class's own parameter names
    assert ("operator", None, "Preview") in [(n, None, t) for n, a, t in log if n == "operator"]


def test_bake_also_saves_files(scene, tmp_path):
    from omninoise.export.images import read_image

    p = scene.omninoise_neural
    p.folder = str(tmp_path) + os.sep
    p.name = "Saved"
    p.save = "EXR"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    np.testing.assert_allclose(read_image(str(tmp_path / "Saved.exr")), _pixels("Saved"), atol=1e-6)
    p.save, p.depth = "PNG", "8"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    np.testing.assert_allclose(read_image(str(tmp_path / "Saved.png")), _pixels("Saved"), atol=1 / 255 + 1e-6)
    assert sorted(os.listdir(tmp_path)) == ["Saved.exr", "Saved.png"]


def test_thumbnails_come_from_the_model_and_are_cached(scene):
    p = scene.omninoise_neural
    assert bpy.ops.omninoise.swatch_thumbnails() == {"FINISHED"}
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.generate import generate
    for i, s in enumerate(p.swatches):
        ima = bpy.data.images[neural_ui.thumbnail_name(i)]
        assert tuple(ima.size) == (32, 32)
        ref = generate(neural_ui.model(), C.uniform(neural_ui.model(), s.spec(), 32, 32), p.seed, 10)
        assert np.abs(_pixels(neural_ui.thumbnail_name(i)) - ref).max() <= 0.5 / 255 + 1e-6
    first = _pixels(neural_ui.thumbnail_name(0)).copy()
    p.swatches[1].p0 = 6.0                    # only the changed swatch is regenerated
    op = neural_ui.OMNINOISE_OT_swatch_thumbnails
    task = op._start(type("Op", (), {"report": lambda *a: None})(), bpy.context, True)
    assert task.status == "done" and list(task.result) == [1]
    np.testing.assert_array_equal(_pixels(neural_ui.thumbnail_name(0)), first)


def test_painted_regions_carry_their_swatch_spectra(scene):
    """Left half painted with spots, right half with damascus: each half's power spectrum is nearer
    its own class's (from uniform samples) than the other's."""
    p = scene.omninoise_neural
    p.mode, p.size, p.steps, p.width = "MAP", 64, 10, 4.0
    bpy.ops.omninoise.blend_map_new()         # first colour left, second right
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    img = _pixels(p.name)
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.generate import generate

    def psd(a):
        a = a - a.mean()
        P = np.abs(np.fft.fft2(a)) ** 2
        f = np.fft.fftfreq(a.shape[0])[:, None], np.fft.fftfreq(a.shape[1])[None, :]
        r = np.minimum((np.hypot(*f) * a.shape[0]).astype(int), a.shape[0] // 2)
        prof = np.bincount(r.ravel(), P.ravel()) / np.maximum(np.bincount(r.ravel()), 1)
        return np.log(prof[1:16] / prof[1:16].sum())

    refs = [np.mean([psd(generate(neural_ui.model(), C.uniform(neural_ui.model(), s.spec(), 64, 64), k, 10)[:, 4:28])
                     for k in range(3)], axis=0) for s in p.swatches]
    left, right = psd(img[:, 4:28]), psd(img[:, 36:60])
    d = lambda a, b: float(np.abs(a - b).mean())  # noqa: E731
    assert d(left, refs[0]) < d(left, refs[1]) and d(right, refs[1]) < d(right, refs[0])


def _material_object():
    bpy.ops.mesh.primitive_plane_add(size=2)
    obj = bpy.context.active_object
    mat = bpy.data.materials.new("Noise")
    obj.data.materials.append(mat)
    return obj, ensure_node_tree(mat)


def _bake_emission(obj, nt, node, size):
    """Cycles bakes the node's colour (as emission) into a size² image through the plane's UVs: (size, size)."""
    for other in [n for n in nt.nodes if n != node]:
        nt.nodes.remove(other)
    em, out = nt.nodes.new("ShaderNodeEmission"), nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(node.outputs["Color"], em.inputs["Color"])
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    target = bpy.data.images.new("bake target", size, size, float_buffer=True)
    target.colorspace_settings.name = "Non-Color"
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = target
    nt.nodes.active = tex
    obj.select_set(True)
    bpy.ops.object.bake(type="EMIT", margin=0)
    px = np.array(target.pixels[:], np.float32).reshape(size, size, 4)
    return np.flipud(px[..., 0])


def test_sequence_bake_writes_the_frames_and_plays_them(scene, tmp_path):
    from omninoise.export.images import read_image
    from omninoise.backend.neural.animate import animate

    p = scene.omninoise_neural
    p.size, p.steps, p.frame_start, p.frame_end = 16, 2, 3, 6
    p.folder, p.name, p.latent = str(tmp_path) + os.sep, "Anim", "slerp"
    scene.render.engine, scene.cycles.device, scene.cycles.samples = "CYCLES", "CPU", 1
    obj, nt = _material_object()
    assert bpy.ops.omninoise.neural_bake_sequence() == {"FINISHED"}
    assert sorted(os.listdir(tmp_path)) == [f"Anim_{f:04d}.exr" for f in range(3, 7)]
    keys = neural_ui.sequence_keys(p)  # swatch 1 on the first frame, swatch 2 on the last, seeds 5 and 6
    assert [(k.frame, k.noise, k.seed) for k in keys] == [(3, "spots", 5), (6, "damascus", 6)]
    ref = dict(animate(neural_ui.model(), keys, (3, 6), 16, 16, latent="slerp", steps=2, sampler=p.sampler))
    for f, img in ref.items():
        np.testing.assert_allclose(read_image(str(tmp_path / f"Anim_{f:04d}.exr")), img, atol=1e-6)
    assert np.abs(ref[3] - ref[6]).mean() > 0.02  # the frames move
    ima = bpy.data.images["Anim Sequence"]
    node = next(n for n in nt.nodes if n.type == "TEX_IMAGE")
    assert ima.source == "SEQUENCE" and node.image == ima and ima.colorspace_settings.name == "Non-Color"
    node.interpolation = "Closest"
    for f in (3, 5, 6):  # scene frame f shows file f in a render
        scene.frame_set(f)
        np.testing.assert_allclose(_bake_emission(obj, nt, node, 16), ref[f], atol=1e-5)


def test_sequence_bake_says_what_is_wrong(scene, tmp_path):
    p = scene.omninoise_neural
    p.folder = str(tmp_path) + os.sep
    p.frame_start, p.frame_end = 10, 4
    with pytest.raises(RuntimeError, match="end frame 4 is before the start 10"):
        bpy.ops.omninoise.neural_bake_sequence()
    p.frame_start, p.frame_end = 1, 1
    with pytest.raises(RuntimeError, match="2 keyframes need at least 2 frames"):
        bpy.ops.omninoise.neural_bake_sequence()
    p.frame_end, p.key_source = 8, "FILE"
    with pytest.raises(RuntimeError, match="pick a keyframe file"):
        bpy.ops.omninoise.neural_bake_sequence()
    bad = tmp_path / "keys.toml"
    bad.write_text('[[key]]\nframe = 1\nnoise = "no_such_class"\n')
    p.keys_file = str(bad)
    with pytest.raises(RuntimeError, match="no_such_class"):
        bpy.ops.omninoise.neural_bake_sequence()
    assert os.listdir(tmp_path) == ["keys.toml"]  # nothing written


def test_fit_to_image_fills_the_active_swatch_as_the_runtime_fits(scene):
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.fit import fit
    from omninoise.backend.neural.generate import generate

    m = neural_ui.model()
    target = generate(m, C.uniform(m, ("cells_f1", {"scale": 10.0}), 32, 32), seed=9, steps=6)
    ima = bpy.data.images.new("target", 32, 32, float_buffer=True)
    rgba = np.ones((32, 32, 4), np.float32)
    rgba[..., :3] = np.flipud(target)[..., None]
    ima.pixels.foreach_set(rgba.ravel())
    p = scene.omninoise_neural
    p.fit_image, p.active = ima, 1
    assert bpy.ops.omninoise.neural_fit() == {"FINISHED"}
    want = fit(m, np.repeat(target[..., None], 3, axis=2), seed=5)  # the panel's seed; 32 px: no bank, every class
    name = max(want.classes, key=want.classes.get)
    sw = p.swatches[1]
    assert sw.noise == name and p.seed == want.seed
    spec = m.class_params[name]["params"]
    assert [round(getattr(sw, f"p{i}"), 4) for i in range(len(spec))] == \
        [round(want.params[name][q["name"]], 4) for q in spec]
    assert bpy.context.window_manager.omninoise_message.startswith("Fit: " + name)
    p.fit_image = None
    with pytest.raises(RuntimeError, match="pick an image to fit"):
        bpy.ops.omninoise.neural_fit()


@pytest.mark.parametrize("mode", ["SINGLE", "CORNERS", "MAP"])
def test_the_panel_builds_the_command_lines_request(scene, mode, tmp_path):
    from omninoise.cli.main import build_parser
    from omninoise.cli.neural import neural_request
    from omninoise.export.images import write_png

    p = scene.omninoise_neural
    p.mode, p.width = mode, 6.0
    while len(p.swatches) < 4:
        bpy.ops.omninoise.swatch_add()
    specs = [s.spec() for s in p.swatches]
    flag = lambda spec: spec[0] + ":" + ",".join(f"{k}={v!r}" for k, v in spec[1].items())  # noqa: E731
    args = ["--size", "32", "--seed", "5", "--steps", "3", "--sampler", p.sampler]
    if mode == "SINGLE":
        p.active = 1
        args += ["--noise", specs[1][0]] + [a for k, v in specs[1][1].items() for a in ("--param", f"{k}={v!r}")]
    elif mode == "CORNERS":
        args += ["--corners"] + [flag(s) for s in specs]
    else:
        bpy.ops.omninoise.blend_map_new()  # swatch 1's colour, swatch 2's on the right half
        ima = p.blend_map
        n = ima.size[0]
        px = np.empty(n * n * 4, np.float32)
        ima.pixels.foreach_get(px)
        write_png(str(tmp_path / "map.png"), np.rint(np.flipud(px.reshape(n, n, 4)[..., :3]) * 255).astype(np.uint8))
        args += ["--map", str(tmp_path / "map.png"), "--width", "6"]    # the panel's width shapes maps only
        for s in p.swatches[:2]:
            args += ["--region", "#%02x%02x%02x=" % tuple(round(c * 255) for c in s.color) + flag(s.spec())]
        args[1] = str(n // 2)  # both draw the map at the image's size, its transitions in the map's pixels
    panel = neural_ui.panel_request(p, int(args[1]))
    cli = neural_request(build_parser().parse_args(["neural", *args, "-o", "x.png"]), neural_ui.model())
    if mode == "MAP":  # the panel lists every swatch; the map uses the first two
        from omninoise.backend.neural.request import map_at

        assert panel.regions.shape == (n // 2, n // 2)      # a map larger than the image is read at its size
        drawn = [map_at(r.regions, r.height, r.width)[0] for r in (panel, cli)]
        assert [s for s in panel.specs[:2]] == list(cli.specs) and np.array_equal(*drawn)
        np.testing.assert_array_equal(panel.conditioning(neural_ui.model()), cli.conditioning(neural_ui.model()))
    else:
        assert panel.key() == cli.key()


@pytest.mark.parametrize("mode, save", [("SINGLE", "EXR"), ("GRADIENT", "PNG"), ("CORNERS", "NONE"), ("MAP", "PNG")])
def test_save_as_job_file_bakes_the_panels_image(scene, tmp_path, mode, save):
    """Each layout saved as a job (the painted map beside it, in the swatches' colours): the panel's file is up to
    date for it, and `omninoise bake --force` writes it again value for value (a Pack Only image as an EXR)."""
    from omninoise.backend.jobs import run_job
    from omninoise.cli.main import main
    from omninoise.export.images import decode

    p = scene.omninoise_neural
    p.folder, p.name, p.mode, p.save, p.width = str(tmp_path) + os.sep, "Job", mode, save, 5.0
    while len(p.swatches) < 4:
        bpy.ops.omninoise.swatch_add()
    p.swatches[2].noise, p.swatches[3].noise = "perlin", "cells_f1"
    if mode == "MAP":
        bpy.ops.omninoise.blend_map_new()   # swatch 1's colour, swatch 2's on the right half
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    panel = {"NONE": lambda: _pixels("Job"),    # the panel kept it in the .blend: its pixels
             "EXR": lambda: decode(str(tmp_path / "Job.exr")), "PNG": lambda: decode(str(tmp_path / "Job.png"))}[save]()
    job = tmp_path / "Job.toml"
    assert bpy.ops.omninoise.neural_save_job(filepath=str(job), target="IMAGE") == {"FINISHED"}
    assert scene.omninoise_bake.job_file == str(job)        # the Batch Job panel runs it next
    text = job.read_text()
    assert {"SINGLE": 'noise = "', "GRADIENT": "gradient = [", "CORNERS": "corners = [", "MAP": "regions = {"}[mode] \
        in text
    assert [o.status for o in run_job(str(job))] == ["baked" if save == "NONE" else "up to date"]
    assert main(["bake", str(job), "--force", "-q"]) == 0
    got = decode(str(tmp_path / ("Job.png" if save == "PNG" else "Job.exr")))
    np.testing.assert_array_equal(got.reshape(panel.shape), panel)
    if mode == "MAP":
        sw = ["#%02x%02x%02x" % tuple(round(c * 255) for c in s.color) for s in p.swatches]
        assert all(f'"{c}" = ' in text for c in sw) and 'map = "Job_map.png"' in text and "width = 5.0" in text
        assert (tmp_path / "Job_map.png").is_file()


def test_save_as_job_file_bakes_the_panels_sequence(scene, tmp_path):
    """The sequence bake (the swatches spread over the frames, a drifting latent, PNG frames) as a job: its frames
    are up to date for it and drawn again the same, its keyframes written out."""
    from omninoise.backend.jobs import run_job
    from omninoise.cli.main import main
    from omninoise.export.images import decode

    p = scene.omninoise_neural
    p.size, p.steps, p.frame_start, p.frame_end = 16, 2, 3, 5
    p.folder, p.name, p.latent, p.drift, p.save = str(tmp_path) + os.sep, "Anim", "drift", 0.25, "PNG"
    assert bpy.ops.omninoise.neural_bake_sequence() == {"FINISHED"}
    names = [f"Anim_{f:04d}.png" for f in range(3, 6)]
    panel = [decode(str(tmp_path / n)) for n in names]
    job = tmp_path / "anim.toml"
    assert bpy.ops.omninoise.neural_save_job(filepath=str(job), target="SEQUENCE") == {"FINISHED"}
    text = job.read_text()
    assert 'noise = "spots"' in text and "seed = 6" in text and "drift = 0.25" in text and "frames = [3, 5]" in text
    assert [o.status for o in run_job(str(job))] == ["up to date"]
    assert main(["bake", str(job), "--force", "-q"]) == 0
    for n, want in zip(names, panel):
        np.testing.assert_array_equal(decode(str(tmp_path / n)), want)
    assert sorted(os.listdir(tmp_path)) == names + ["anim.toml"]


def test_save_as_job_file_says_what_is_wrong(scene, tmp_path):
    """No swatch, a .json name, a job whose map would be written over the painted blend map's own file: one line,
    and nothing written."""
    p = scene.omninoise_neural
    p.folder, p.mode = str(tmp_path) + os.sep, "MAP"
    with pytest.raises(RuntimeError, match="a job file is a .toml file"):
        bpy.ops.omninoise.neural_save_job(filepath=str(tmp_path / "a.json"))
    bpy.ops.omninoise.blend_map_new()
    painted = p.blend_map
    painted.filepath_raw, painted.file_format = str(tmp_path / "paint_map.png"), "PNG"
    painted.save()
    kept = (tmp_path / "paint_map.png").read_bytes()
    with pytest.raises(RuntimeError, match="the job writes its map to paint_map.png, the file of an image the panel"):
        bpy.ops.omninoise.neural_save_job(filepath=str(tmp_path / "paint.toml"))
    assert (tmp_path / "paint_map.png").read_bytes() == kept
    while p.swatches:
        bpy.ops.omninoise.swatch_remove()
    with pytest.raises(RuntimeError, match="add a swatch first"):
        bpy.ops.omninoise.neural_save_job(filepath=str(tmp_path / "a.toml"))
    assert os.listdir(tmp_path) == ["paint_map.png"]
