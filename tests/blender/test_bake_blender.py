"""Bake operators in background Blender: ramps, Volume objects, images, tasks, jobs."""
import os
import threading
import time

import numpy as np
import pytest
from conftest import needs_openvdb

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from omninoise.backend.bake import BakeSpec, run_bake  # noqa: E402
from omninoise.backend.sources import BoxGrid, WaveSource  # noqa: E402
from omninoise.backend.transfer import preset  # noqa: E402
from omninoise.blender_addon.bake_ui import apply_transfer  # noqa: E402
from omninoise.export import read_volume  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon():
    blender_addon.register()
    yield
    blender_addon.unregister()


@pytest.fixture
def scene(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    sc = bpy.context.scene
    p = sc.omninoise_bake
    p.folder = str(tmp_path) + os.sep
    p.bounds_mode = "CUSTOM"
    p.bounds_min, p.bounds_max = (-1.0, -1.0, -0.5), (1.0, 1.0, 0.5)
    p.volume_resolution = (24, 24, 12)
    p.image_resolution = (32, 24)
    p.wave.dimensions = "3"
    p.wave.seed = 3
    p.wave.fmin, p.wave.fmax = 1.0, 4.0
    return sc


def _ramp(mode, colour_mode="RGB"):
    from omninoise.blender_addon.bake_blender import ramp_node

    cr = ramp_node().color_ramp
    cr.color_mode = colour_mode
    cr.interpolation = mode
    while len(cr.elements) < 3:
        cr.elements.new(0.5)
    for e, (p, c) in zip(cr.elements, [(0.1, (1, 0, 0, 0.2)), (0.45, (0, 1, 0.5, 1)), (0.8, (0.2, 0.1, 1, 0.6))]):
        e.position, e.color = p, c
    return cr


@pytest.mark.parametrize("mode", ["LINEAR", "CONSTANT", "EASE", "B_SPLINE", "CARDINAL"])
def test_transfer_equals_blender_color_ramp(scene, mode):
    from omninoise.blender_addon.bake_blender import transfer_from_color_ramp

    cr = _ramp(mode)
    tf = transfer_from_color_ramp(cr, (0.0, 1.0))
    t = np.linspace(0, 1, 401, dtype=np.float32)
    t = t[np.min(np.abs(t[:, None] - np.array([0.1, 0.45, 0.8])[None]), 1) > 1e-3]  # away from hard steps
    ours = tf.rgba(t)
    blender = np.array([cr.evaluate(float(x)) for x in t], np.float32)
    tol = 1e-5 if mode in ("LINEAR", "CONSTANT", "EASE") else 2e-3  # sampled at 257 positions
    np.testing.assert_allclose(ours, blender, atol=tol)


def test_presets_set_the_ramp(scene):
    from omninoise.blender_addon.bake_blender import ramp_node

    p = scene.omninoise_bake
    for name in ("fire", "marble", "clouds"):
        apply_transfer(p, preset(name))
        cr = ramp_node().color_ramp
        ref = preset(name)
        assert [round(e.position, 5) for e in cr.elements] == [round(x, 5) for x, _ in ref.stops]
        np.testing.assert_allclose([tuple(e.color) for e in cr.elements], [c for _, c in ref.stops], atol=1e-6)
        assert (p.range_min, p.range_max) == pytest.approx(ref.range)
        assert p.use_temperature == ref.has_temperature


@needs_openvdb
def test_bake_volume_operator_makes_a_renderable_volume(scene, tmp_path):
    p = scene.omninoise_bake
    apply_transfer(p, preset("smoke"))  # dark smoke: absorbs the white world where it is dense
    p.density_scale = 20.0
    p.name = "Clouds"
    assert bpy.ops.omninoise.bake_volume() == {"FINISHED"}
    path = str(tmp_path / "Clouds.vdb")
    assert os.path.isfile(path)
    obj = bpy.data.objects["Clouds"]
    vol = obj.data
    assert sorted(g.name for g in vol.grids) == ["color", "density"]
    pv = next(n for n in vol.materials[0].node_tree.nodes if n.type == "PRINCIPLED_VOLUME")
    assert pv.inputs["Density Attribute"].default_value == "density"
    assert pv.inputs["Color Attribute"].default_value == "color"
    # the same bake through the Blender-free pipeline gives the same voxels
    from omninoise.blender_addon.bake_ui import transfer

    spec = BakeSpec("ref", WaveSource(p.wave.to_settings(node=False)), BoxGrid((24, 24, 12),
                    ((-1, -1, -0.5), (1, 1, 0.5))), str(tmp_path / "ref.vdb"), transfer(p))
    run_bake(spec)
    np.testing.assert_array_equal(read_volume(path, "density", (12, 24, 24)),
                                  read_volume(spec.output, "density", (12, 24, 24)))
    # Cycles renders it: the white world shows through where the smoke is thin, not where it is dense
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    cam.location = (0, 0, 6)
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = 2.0
    scene.camera = cam
    world = bpy.data.worlds.new("w")
    world.color = (1, 1, 1)
    # new worlds use nodes in 5.0 (and after use_nodes before): the Background node is what renders
    bg = next(n for n in ensure_node_tree(world).nodes if n.type == "BACKGROUND")
    bg.inputs["Color"].default_value = (1, 1, 1, 1)
    scene.world = world
    r = scene.render
    r.engine = "CYCLES"
    scene.cycles.samples = 64  # 8 left the rank correlation at -0.46 on bpy 4.5 (noise, not the volume)
    scene.cycles.device = "CPU"
    scene.view_settings.view_transform = "Standard"
    r.resolution_x = r.resolution_y = 24
    r.filepath = str(tmp_path / "render.png")
    r.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(r.filepath)
    px = np.array(img.pixels[:], np.float32).reshape(24, 24, 4)[..., :3].mean(-1)
    d = read_volume(path, "density", (12, 24, 24)).sum(0)  # optical depth per column (y, x)
    thick, thin = d > np.quantile(d, 0.8), d < np.quantile(d, 0.2)
    rank = lambda v: np.argsort(np.argsort(v.ravel()))  # noqa: E731
    spearman = np.corrcoef(rank(px), rank(d))[0, 1]
    assert px[thin].mean() > px[thick].mean() + 0.02 and spearman < -0.5, (px[thin].mean(), px[thick].mean(),
                                                                            spearman)


@needs_openvdb
def test_animated_volume_is_a_sequence(scene, tmp_path):
    p = scene.omninoise_bake
    p.wave.speed = 2.0
    p.animated, p.frame_start, p.frame_end = True, 3, 5
    p.name = "Anim"
    apply_transfer(p, preset("fire"))
    assert bpy.ops.omninoise.bake_volume() == {"FINISHED"}
    assert sorted(os.listdir(tmp_path)) == ["Anim_0003.vdb", "Anim_0004.vdb", "Anim_0005.vdb"]
    vol = bpy.data.objects["Anim"].data
    assert vol.is_sequence and vol.frame_duration == 3
    for f in (3, 4, 5):
        scene.frame_set(f)
        vol.grids.load()
        assert vol.grids.frame_filepath.endswith(f"Anim_{f:04d}.vdb")
    assert "temperature" in [g.name for g in vol.grids]
    nodes = vol.materials[0].node_tree.nodes
    assert next(n for n in nodes if n.type == "PRINCIPLED_VOLUME").inputs["Blackbody Intensity"].default_value == 1.0


def test_bake_image_operator(scene, tmp_path):
    p = scene.omninoise_bake
    p.name = "Marble"
    apply_transfer(p, preset("marble"))
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}
    img = bpy.data.images["Marble"]
    assert tuple(img.size) == (32, 24)
    mat = bpy.data.materials["OmniNoise Marble"]
    tex = next(n for n in mat.node_tree.nodes if n.type == "TEX_IMAGE")
    assert tex.image == img and tex.outputs["Color"].is_linked
    p.use_ramp = False
    p.image_format = "PNG"
    p.name = "Raw"
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}
    assert bpy.data.images["Raw"].colorspace_settings.name == "Non-Color"
    # an animated image bake is an EXR sequence that the Image Texture node plays
    p.wave.speed, p.animated, p.frame_start, p.frame_end = 1.0, True, 2, 4
    p.image_format, p.name = "EXR", "Seq"
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}
    assert sorted(f for f in os.listdir(tmp_path) if f.startswith("Seq")) == \
        ["Seq_0002.exr", "Seq_0003.exr", "Seq_0004.exr"]
    img = bpy.data.images["Seq"]
    tex = next(n for n in bpy.data.materials["OmniNoise Seq"].node_tree.nodes if n.type == "TEX_IMAGE")
    assert img.source == "SEQUENCE" and tex.image_user.frame_duration == 3 and tex.image_user.frame_start == 2


def test_an_unsaved_files_bake_goes_to_the_user_cache_where_a_script_registered_the_package(scene):
    """Registered by a script from the installed Python package (``omninoise.register()``, as these tests do),
    not loaded by Blender as an extension, a bake of an unsaved file into the default folder ('//omninoise/')
    goes to the user's cache folder (``$XDG_CACHE_HOME/omninoise`` here), which outlives the Blender session as an
    extension's user folder does; not to Blender's temporary folder, which goes with it."""
    from omninoise.blender_addon import preferences

    assert not preferences.ROOT_PACKAGE.startswith("bl_ext.") and not bpy.data.filepath
    p = scene.omninoise_bake
    p.folder, p.name = "//omninoise/", "Cached"
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}
    path = os.path.abspath(bpy.path.abspath(bpy.data.images["Cached"].filepath))
    cache = os.path.join(os.environ["XDG_CACHE_HOME"], "omninoise")
    assert preferences.cache_dir() == cache and os.path.isfile(path)
    assert path.startswith(os.path.join(cache, "omninoise")) and not path.startswith(bpy.app.tempdir)


def test_the_threads_preference_is_at_most_the_machine_s_cpus(monkeypatch):
    """Preferences travel between machines: CPU Threads 256 saved on a workstation, on a machine of 2 CPUs, would
    make every bake's threads wait on each other (neural noise 15 times as long at 64 threads). It is read as at
    most the CPUs this machine gives Blender; 0 is all of them."""
    from types import SimpleNamespace

    from omninoise.backend import limits
    from omninoise.blender_addon import preferences

    monkeypatch.setattr(limits, "cpus", lambda: 2)
    for asked, got in ((0, 2), (1, 1), (2, 2), (256, 2)):
        monkeypatch.setattr(preferences, "get", lambda: SimpleNamespace(threads=asked))
        assert preferences.threads() == got
    monkeypatch.setattr(preferences, "get", lambda: None)
    assert preferences.threads() == 2


def test_bad_settings_report_one_line(scene, tmp_path):
    p = scene.omninoise_bake
    p.wave.dimensions = "2"
    with pytest.raises(RuntimeError, match="a volume needs 3D or 4D noise"):
        bpy.ops.omninoise.bake_volume()
    p.wave.dimensions = "3"
    p.bounds_mode = "OBJECT"
    with pytest.raises(RuntimeError, match="no active object"):
        bpy.ops.omninoise.bake_volume()
    bpy.ops.object.empty_add()
    with pytest.raises(RuntimeError, match="bounds: the active object 'Empty' has no size along x, y, z: select"):
        bpy.ops.omninoise.bake_volume()
    bpy.ops.mesh.primitive_plane_add()
    with pytest.raises(RuntimeError, match="'Plane' has no size along z"):
        bpy.ops.omninoise.bake_volume()
    assert os.listdir(tmp_path) == []
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}       # a plane's image covers its x and y
    with pytest.raises(RuntimeError, match=r"transfer function preset: none given \(a preset passes"):
        bpy.ops.omninoise.set_transfer()
    with pytest.raises(RuntimeError, match="transfer function preset: .*needs stops"):
        bpy.ops.omninoise.set_transfer(transfer='{"range": [1, 0]}')
    p.wave.fmin = 9.0                       # the panel's names, not the settings' (spectrum.fmin, range)
    with pytest.raises(RuntimeError, match=r"Min Frequency: 9 is greater than fmax \d"):
        bpy.ops.omninoise.bake_image()
    p.wave.fmin, p.range_min, p.range_max = 2.0, 0.5, 0.5
    with pytest.raises(RuntimeError, match=r"From and To: needs two different values, at least 1e-06 apart, "
                                           r"got \(0.5, 0.5\)"):
        bpy.ops.omninoise.bake_image()
    p.range_min, p.range_max = -1e300, 1e300      # held where the ramp's positions stay finite
    assert (p.range_min, p.range_max) == (-1e6, 1e6)
    from omninoise.blender_addon.bake_blender import ramp_node

    p.range_min, p.range_max, p.half = -0.2, 1.6, True     # a colour past a half float's 65504 was written infinite
    element = ramp_node().color_ramp.elements[-1]
    colour, element.color = tuple(element.color), (1e5, 1.0, 1.0, 1.0)
    with pytest.raises(RuntimeError, match="Half Float: the ramp writes values up to 100000"):
        bpy.ops.omninoise.bake_image()
    element.color, p.half = colour, False
    p.range_max, p.animated, p.time_per_frame = 1.0, True, float("nan")
    with pytest.raises(RuntimeError, match="Time per Frame: must be a finite number, got nan"):
        bpy.ops.omninoise.bake_image()
    p.animated = False
    (tmp_path / "a_file").write_text("")
    p.folder = str(tmp_path / "a_file")
    with pytest.raises(RuntimeError, match="folder: .*a_file is a file, not a folder"):
        bpy.ops.omninoise.bake_image()
    with pytest.raises(RuntimeError, match="job file: pick a TOML job file to run"):
        bpy.ops.omninoise.run_job()
    with pytest.raises(RuntimeError, match="job file: no file at .*missing.toml"):
        bpy.ops.omninoise.run_job(filepath=str(tmp_path / "missing.toml"))


@needs_openvdb
def test_worker_keeps_main_thread_free_and_cancels(scene, tmp_path):
    from omninoise.blender_addon import tasks

    src = WaveSource(scene.omninoise_bake.wave.to_settings(node=False).replace(directions=32))
    spec = BakeSpec("big", src, BoxGrid((160, 160, 160)), str(tmp_path / "big.vdb"), preset("smoke"))
    done = []
    task = tasks.start(tasks.Task("big", lambda pr, c: run_bake(spec, pr, c), done.append))
    ticks = 0
    while task._thread.is_alive() and task.progress < 0.2:
        time.sleep(0.01)
        ticks += 1  # the main thread runs while the worker bakes (kernels release the GIL)
    assert ticks > 3
    assert tasks.start is not None and tasks.current() is task
    with pytest.raises(RuntimeError, match="busy"):
        tasks.start(tasks.Task("second", lambda pr, c: None))
    task.cancel()
    tasks.wait(task)
    assert task.status == "cancelled" and not done and tasks.current() is None
    assert os.listdir(tmp_path) == []
    # and a task that finishes runs its callback on the main thread
    small = BakeSpec("small", src, BoxGrid((16, 16, 16)), str(tmp_path / "small.vdb"))
    main = threading.get_ident()
    seen = []
    t2 = tasks.start(tasks.Task("small", lambda pr, c: run_bake(small, pr, c),
                                lambda r: seen.append((threading.get_ident(), r.written))))
    tasks.wait(t2)
    assert t2.status == "done" and seen == [(main, [small.output])] and t2.progress == 1.0


JOB = """
[[bake]]
name = "vol"
output = "vol.vdb"
resolution = [16, 16, 8]
bounds = [[-1, -1, 0], [1, 1, 1]]
transfer = "smoke"
[bake.source]
dim = 3
seed = 9

[[bake]]
name = "img"
output = "img.exr"
resolution = [24, 16]
[bake.source]
dim = 2
"""


@needs_openvdb
def test_job_in_blender_matches_the_command_line(tmp_path):
    from omninoise.cli.main import main

    for sub in ("cli", "bpy"):
        (tmp_path / sub).mkdir()
        (tmp_path / sub / "job.toml").write_text(JOB)
    assert main(["bake", str(tmp_path / "cli" / "job.toml"), "--quiet"]) == 0
    assert bpy.ops.omninoise.run_job(filepath=str(tmp_path / "bpy" / "job.toml")) == {"FINISHED"}
    for name in ("vol.vdb", "img.exr"):
        a, b = tmp_path / "cli" / name, tmp_path / "bpy" / name
        from omninoise.export import read_metadata

        assert read_metadata(str(a))["omninoise_key"] == read_metadata(str(b))["omninoise_key"]
    np.testing.assert_array_equal(read_volume(str(tmp_path / "cli" / "vol.vdb"), "density", (8, 16, 16)),
                                  read_volume(str(tmp_path / "bpy" / "vol.vdb"), "density", (8, 16, 16)))
    (tmp_path / "bpy" / "job.toml").write_text(JOB.replace("seed = 9", "sed = 9"))
    with pytest.raises(RuntimeError, match=r"bake 'vol': source.sed: unknown key \(did you mean seed\?\)"):
        bpy.ops.omninoise.run_job(filepath=str(tmp_path / "bpy" / "job.toml"))


@pytest.mark.parametrize("target", [pytest.param("VOLUME", marks=needs_openvdb), "IMAGE"])
def test_a_bake_saved_as_a_job_bakes_the_same_files_without_blender(scene, tmp_path, target):
    """Save as Job File writes the panel's bake (its wave settings, a sampled B-spline ramp, frames, box) as a job;
    `omninoise bake` finds the panel's files up to date, and baked again (--force) they are the same values."""
    from omninoise.backend.jobs import run_job
    from omninoise.blender_addon.bake_ui import build_spec
    from omninoise.cli.main import main
    from omninoise.export.images import decode

    p = scene.omninoise_bake
    p.wave.spectrum, p.wave.exponent, p.wave.speed = "bandpass", 1.7, 0.4    # the exponent reads nothing here
    p.use_ramp = True
    _ramp("B_SPLINE")
    p.animated, p.frame_start, p.frame_end, p.time_per_frame = True, 2, 3, 0.25
    p.name, p.image_format = "Saved", "EXR"
    bake = bpy.ops.omninoise.bake_volume if target == "VOLUME" else bpy.ops.omninoise.bake_image
    assert bake() == {"FINISHED"}
    spec = build_spec(bpy.context, target)
    frames = [spec.output.replace("####", f"{f:04d}") for f in (2, 3)]

    def values(path):
        if target == "VOLUME":
            return np.concatenate([read_volume(path, "density", (12, 24, 24))[..., None],
                                   read_volume(path, "color", (12, 24, 24))], axis=3)
        return decode(path)
    panel = [values(f) for f in frames]
    job = tmp_path / "jobs" / "saved.toml"
    job.parent.mkdir()
    assert bpy.ops.omninoise.save_job(filepath=str(job), target=target) == {"FINISHED"}
    assert scene.omninoise_bake.job_file == str(job)            # the Batch Job panel runs it next
    text = job.read_text()
    assert "exponent" not in text and "[bake.transfer]" in text and "output_root" in text
    assert [o.status for o in run_job(str(job))] == ["up to date"]
    assert main(["bake", str(job), "--force", "-q"]) == 0
    for f, want in zip(frames, panel):
        np.testing.assert_array_equal(values(f), want)


def test_save_as_job_file_refuses_what_a_job_cannot_hold(scene, tmp_path):
    p = scene.omninoise_bake
    p.wave.dimensions = "2"
    with pytest.raises(RuntimeError, match="a volume needs 3D or 4D noise"):
        bpy.ops.omninoise.save_job(filepath=str(tmp_path / "a.toml"), target="VOLUME")
    p.wave.dimensions = "3"
    with pytest.raises(RuntimeError, match="a job file is a .toml file"):
        bpy.ops.omninoise.save_job(filepath=str(tmp_path / "a.json"), target="IMAGE")
    assert not [f for f in os.listdir(tmp_path) if f.endswith((".toml", ".json"))]


def test_a_node_group_bake_saved_as_a_job_holds_the_groups_settings(scene, tmp_path):
    """Source Node Group: the job holds the Wave Noise group's own settings (not the panel's), with the bake's
    output part and cellular mode, and bakes the panel's image."""
    from omninoise.backend import Spectrum, WaveSettings
    from omninoise.backend.jobs import run_job
    from omninoise.blender_addon.wave_nodes import build_wave_group
    from omninoise.export.images import decode

    group = build_wave_group(WaveSettings(dim=3, spectrum=Spectrum("fractal", 1.0, 5.0, 0.75), waveform="crystal",
                                          directions=7, seed=12), name="Grain")
    p = scene.omninoise_bake
    p.source, p.node_group, p.output, p.cellular = "NODE", group, "modulus", "polytope"
    p.name, p.image_format = "FromGroup", "EXR"
    assert bpy.ops.omninoise.bake_image() == {"FINISHED"}
    path = str(tmp_path / "FromGroup.exr")
    baked = decode(path)
    job = tmp_path / "group.toml"
    assert bpy.ops.omninoise.save_job(filepath=str(job), target="IMAGE") == {"FINISHED"}
    text = job.read_text()
    for line in ('directions = 7', 'seed = 12', 'waveform = "crystal"', 'output = "modulus"',
                 'cellular = "polytope"', 'exponent = 0.75'):
        assert line in text, line
    assert [o.status for o in run_job(str(job), force=True)] == ["baked"]
    np.testing.assert_array_equal(decode(path), baked)
