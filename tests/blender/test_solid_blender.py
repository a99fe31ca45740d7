"""Solid Texture from Image in background Blender: preview, UV image, colour attribute and volume bakes."""
import os
import shutil

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import backend, blender_addon  # noqa: E402
from conftest import Recorder, needs_openvdb  # noqa: E402
from omninoise.blender_addon import common, solid_ui, tasks  # noqa: E402
from omninoise.backend.solid.bake import srgb_to_linear  # noqa: E402
from omninoise.backend.solid.model import SolidTextureModel  # noqa: E402
from omninoise.backend.solid.pipeline import photo_code  # noqa: E402

SHIPPED = solid_ui.models_dir()
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module", autouse=True)
def addon(tmp_path_factory):
    """A models folder with the shipped gravel model and the shipped texture-space model (no torch needed)."""
    root = tmp_path_factory.mktemp("solid_models")
    for name in ("gravel_3d", "space"):
        shutil.copytree(os.path.join(SHIPPED, name), root / name)
    solid_ui.MODELS_DIR = str(root)
    blender_addon.register()
    yield
    blender_addon.unregister()
    solid_ui.MODELS_DIR = None


@pytest.fixture
def scene(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    p = bpy.context.scene.omninoise_solid
    p.texture = "single:gravel_3d"
    p.size, p.margin, p.voxels, p.seed, p.scale = 32, 2, 8, 3, 2.0
    p.folder = str(tmp_path)
    return bpy.context.scene


def _model(name="gravel_3d"):
    return SolidTextureModel(os.path.join(solid_ui.models_dir(), name))


def _pixels(name):
    ima = bpy.data.images[name]
    w, h = ima.size
    px = np.empty(w * h * 4, np.float32)
    ima.pixels.foreach_get(px)
    return px.reshape(h, w, 4)[..., :3]


def test_catalogue_lists_single_models_and_space_exemplars(scene):
    ids = [i[0] for i in solid_ui._catalogue()]
    space = _model("space")
    assert ids == ["single:gravel_3d"] + [f"space:space:{n}" for n in sorted(space.codes)]
    assert {"gravel", "grass", "wood"} <= set(space.codes)


def test_uv_image_bake_is_the_texture_at_each_texels_surface_point(scene):
    bpy.ops.mesh.primitive_plane_add(size=2.0)      # UV [0,1]^2 -> object xy [-1,1]^2
    obj = bpy.context.active_object
    obj.location = (5.0, 0.0, 0.0)                   # object coordinates: the location does not matter
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    got = _pixels("Solid Texture")                   # row 0 = bottom = v 0
    j, i = np.meshgrid(np.arange(32), np.arange(32))
    pts = np.stack([-1 + 2 * (j + 0.5) / 32, -1 + 2 * (i + 0.5) / 32, np.zeros_like(j, float)], -1).reshape(-1, 3)
    m = _model()
    ref = m.evaluate(pts * 2.0, m.default_code(), seed=3).reshape(32, 32, 3)
    assert np.abs(got - ref).max() <= 0.5 / 255 + 1e-6   # 8-bit sRGB image
    mat = obj.active_material
    tex = next(n for n in mat.node_tree.nodes if n.type == "TEX_IMAGE")
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    assert tex.image.name == "Solid Texture" and bsdf.inputs["Base Color"].links[0].from_node == tex
    # world coordinates follow the location
    scene.omninoise_solid.coords = "WORLD"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    pts_w = pts + [5.0, 0.0, 0.0]
    ref_w = m.evaluate(pts_w * 2.0, m.default_code(), seed=3).reshape(32, 32, 3)
    assert np.abs(_pixels("Solid Texture") - ref_w).max() <= 0.5 / 255 + 1e-6


def test_cube_seams_agree(scene):
    """Texels on both sides of a cube edge (two UV islands) agree as well as the texture itself does between
    their 3D points (no seam: the baked colours differ across the edge no more than the runtime's at the same
    points; a texture with fine grain differs over the texel's width anyway)."""
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    p = scene.omninoise_solid
    p.size, p.scale = 256, 0.25
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    from omninoise.blender_addon.solid_ui import _mesh_arrays
    from omninoise.backend.solid.surface import texel_positions
    uv, pos = _mesh_arrays(bpy.context, bpy.context.active_object, False, True)
    mask, pts = texel_positions(uv, pos, 256, 256)
    img = _pixels("Solid Texture")
    # texels within half a texel of the edge x = 1, y = 1 on the two faces that share it
    near = mask & (np.abs(pts[..., 0] - 1) < 1e-9) & (pts[..., 1] > 1 - 2 / 64)
    near2 = mask & (np.abs(pts[..., 1] - 1) < 1e-9) & (pts[..., 0] > 1 - 2 / 64)
    assert near.sum() > 10 and near2.sum() > 10
    za = pts[near][:, 2]
    zb = pts[near2][:, 2]
    ca, cb = img[near], img[near2]
    # colours as a function of z along the edge, interpolated: the two faces agree
    m = _model()
    ra, rb = (m.evaluate(q * 0.25, m.default_code(), seed=3) for q in (pts[near], pts[near2]))
    order = np.argsort(zb)
    for c in range(3):
        baked = np.abs(np.interp(za, zb[order], cb[order, c]) - ca[:, c]).mean()
        texture = np.abs(np.interp(za, zb[order], rb[order, c]) - ra[:, c]).mean()
        assert baked < texture + 0.01 and baked < 0.15


def test_color_attribute_bake(scene):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    obj = bpy.context.active_object
    p = scene.omninoise_solid
    p.target = "COLOR_ATTRIBUTE"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    me = obj.data
    attr = me.color_attributes["Solid Texture"]
    assert attr.domain == "POINT" and attr.data_type == "FLOAT_COLOR"
    got = np.empty(len(me.vertices) * 4, np.float32)
    attr.data.foreach_get("color", got)
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    m = _model()
    ref = srgb_to_linear(m.evaluate(co.reshape(-1, 3).astype(np.float64) * 2.0, m.default_code(), seed=3))
    np.testing.assert_allclose(got.reshape(-1, 4)[:, :3], ref, atol=1e-5)
    node = next(n for n in obj.active_material.node_tree.nodes if n.type == "VERTEX_COLOR")
    assert node.layer_name == "Solid Texture"



def test_a_uv_image_too_large_for_memory_is_refused_before_any_work(scene):
    bpy.ops.mesh.primitive_plane_add()
    scene.omninoise_solid.size = 200000
    with pytest.raises(RuntimeError, match=r"image size: a 200000² UV image bake needs 4768\.4 GiB, above the limit"):
        bpy.ops.omninoise.solid_bake()
    assert "Solid Texture" not in bpy.data.images

def test_a_uv_map_that_covers_no_pixel_is_refused_not_baked_black(scene):
    """Every face's UVs at one point, or faces too small to hold a pixel's centre: one line naming the UV map,
    found before the texture is made, and no black image."""
    bpy.ops.mesh.primitive_cube_add()
    uv = bpy.context.active_object.data.uv_layers.active
    a = np.empty(len(uv.data) * 2, np.float32)
    uv.data.foreach_get("uv", a)
    for squeezed in (np.zeros_like(a), a * 0.001 + 0.3):
        uv.data.foreach_set("uv", squeezed.astype(np.float32))
        bpy.context.active_object.data.update()         # as an edit in the UV editor tags it
        with pytest.raises(RuntimeError, match=r"uv: the UV map of 'Cube' covers no pixel of the image: unwrap it"):
            bpy.ops.omninoise.solid_bake()
        assert "Solid Texture" not in bpy.data.images
    uv.data.foreach_set("uv", a)
    bpy.context.active_object.data.update()
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}

def test_color_attribute_bake_in_edit_mode_is_of_the_edited_mesh_and_survives_leaving_it(scene):
    """In Edit Mode the mesh data holds the shape Edit Mode began with and Blender writes the edit mesh back over
    it on leaving: the bake reads the edited vertices and its colors are still there in Object Mode."""
    import bmesh

    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    scene.omninoise_solid.target = "COLOR_ATTRIBUTE"
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=2, use_grid_fill=True)
    for v in bm.verts:
        v.co *= 1.5
    bmesh.update_edit_mesh(obj.data)
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")
    me = obj.data
    assert len(me.vertices) == 56
    got = np.empty(len(me.vertices) * 4, np.float32)
    me.color_attributes["Solid Texture"].data.foreach_get("color", got)
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    assert np.abs(co).max() == pytest.approx(1.5)
    m = _model()
    ref = srgb_to_linear(m.evaluate(co.reshape(-1, 3).astype(np.float64) * 2.0, m.default_code(), seed=3))
    np.testing.assert_allclose(got.reshape(-1, 4)[:, :3], ref, atol=1e-5)
    assert me.color_attributes.active_color.name == "Solid Texture"


def test_a_mesh_changed_while_its_color_bake_ran_is_named_not_an_internal_error(scene):
    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    with pytest.raises(backend.SettingError, match="'Cube' has 8 vertices, the bake was of 9: the mesh changed"):
        solid_ui._store_vertex_colors(obj, "Solid Texture", np.zeros((9, 3), np.float32))
    assert "Solid Texture" not in obj.data.color_attributes

    def done(rgb):
        solid_ui._store_vertex_colors(obj, "Solid Texture", rgb)

    task = tasks.start(tasks.Task("t", lambda progress, cancel: np.zeros((9, 3), np.float32), done), blocking=True)
    assert task.status == "failed" and task.message.startswith("object: 'Cube' has 8 vertices")
    assert isinstance(task.error, backend.SettingError)     # the operator names it as the panel does

@needs_openvdb
def test_volume_bake(scene, tmp_path):
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(1.0, 0.0, 0.0))
    p = scene.omninoise_solid
    p.target = "VOLUME"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    path = tmp_path / "Solid_Texture.vdb"
    assert path.is_file()
    from omninoise.export.vdb import read_volume
    col = read_volume(str(path), "color", (8, 8, 8))
    # voxel centres of the object's local bounds [-1, 1]^3 at 8 voxels
    c = -1 + (np.arange(8) + 0.5) * 0.25
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    m = _model()
    ref = srgb_to_linear(m.evaluate(np.stack([x, y, z], -1).reshape(-1, 3) * 2.0, m.default_code(), 3))
    np.testing.assert_allclose(col.reshape(-1, 3), ref, atol=1e-5)
    vol = bpy.data.objects["Solid Texture"]
    assert vol.type == "VOLUME" and tuple(vol.matrix_world.translation) == pytest.approx((1.0, 0.0, 0.0))


@needs_openvdb
@pytest.mark.parametrize("source", ["SHIPPED", "IMAGE"])
def test_save_as_job_file_bakes_the_panels_volume(scene, tmp_path, source):
    """The volume bake saved as a job (an image exemplar written beside it as a PNG of its pixels): `omninoise bake`
    writes the panel's volume again, for a shipped texture and a photo's spectral solid, in world positions."""
    from omninoise.backend.jobs import run_job
    from omninoise.export.images import decode, write_png
    from omninoise.export.vdb import read_volume

    p = scene.omninoise_solid
    p.target, p.coords, p.name = "VOLUME", "WORLD", "Block"
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.5, 0.0, 0.0))
    if source == "IMAGE":
        rgb = np.random.default_rng(4).integers(0, 256, (64, 72, 3)).astype(np.uint8)
        write_png(str(tmp_path / "ex.png"), rgb)
        p.source, p.image, p.method = "IMAGE", bpy.data.images.load(str(tmp_path / "ex.png")), "SPECTRAL"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    panel = read_volume(str(tmp_path / "Block.vdb"), "color", (8, 8, 8))
    job = tmp_path / "block.toml"
    assert bpy.ops.omninoise.solid_save_job(filepath=str(job)) == {"FINISHED"}
    assert scene.omninoise_bake.job_file == str(job)        # the Batch Job panel runs it next
    text = job.read_text()
    assert "scale = 2.0" in text and "seed = 3" in text and "bounds = [[-0.5, -1.0, -1.0], [1.5, 1.0, 1.0]]" in text
    if source == "IMAGE":       # the photo's own 8-bit values, named from the job's folder
        assert 'exemplar = "block_photo.png"' in text and 'method = "spectral"' in text
        assert np.array_equal(np.rint(decode(str(tmp_path / "block_photo.png")) * 255), rgb)
    os.remove(tmp_path / "Block.vdb")
    assert [o.status for o in run_job(str(job))] == ["baked"]
    np.testing.assert_allclose(read_volume(str(tmp_path / "Block.vdb"), "color", (8, 8, 8)), panel, atol=2e-5)


def test_save_as_job_file_says_what_is_wrong(scene, tmp_path):
    """A UV image bake (written into the mesh), a .json name: one line, nothing written."""
    bpy.ops.mesh.primitive_cube_add()
    p = scene.omninoise_solid
    with pytest.raises(RuntimeError, match="A job bakes files: set Bake To to Volume"):
        bpy.ops.omninoise.solid_save_job(filepath=str(tmp_path / "a.toml"))
    p.target = "VOLUME"
    with pytest.raises(RuntimeError, match="a job file is a .toml file"):
        bpy.ops.omninoise.solid_save_job(filepath=str(tmp_path / "a.json"))
    assert os.listdir(tmp_path) == []


@needs_openvdb
def test_save_as_job_file_never_writes_the_photo_over_the_exemplars_file(scene, tmp_path):
    """A job whose photo would be written over the Exemplar image's own file: one line, the file as it was."""
    from omninoise.export.images import write_png

    bpy.ops.mesh.primitive_cube_add()
    p = scene.omninoise_solid
    p.target = "VOLUME"
    write_png(str(tmp_path / "wall_photo.png"), np.full((64, 64, 3), 90, np.uint8))
    kept = (tmp_path / "wall_photo.png").read_bytes()
    p.source, p.image, p.method = "IMAGE", bpy.data.images.load(str(tmp_path / "wall_photo.png")), "SPECTRAL"
    with pytest.raises(RuntimeError, match="the job writes its photo to wall_photo.png, the file of the Exemplar"):
        bpy.ops.omninoise.solid_save_job(filepath=str(tmp_path / "wall.toml"))
    assert os.listdir(tmp_path) == ["wall_photo.png"] and (tmp_path / "wall_photo.png").read_bytes() == kept


@needs_openvdb
def test_the_spectral_solid_previews_and_bakes_as_the_command_line_draws_it(scene, tmp_path):
    """Method Spectral Solid (backend/solid/spectral_solid.py): the panel's request is the command line's (Periodic
    Part included); the preview, a colour attribute and a volume are the request's solid read at the same points;
    the panel hides the neural texture's other settings."""
    from omninoise.backend.solid.spectral_solid import SpectralTexture
    from omninoise.cli.main import build_parser
    from omninoise.cli.solid import solid_request
    from omninoise.export.images import write_png

    rgb = np.random.default_rng(4).integers(0, 256, (64, 72, 3)).astype(np.uint8)
    write_png(str(tmp_path / "ex.png"), rgb)
    p = scene.omninoise_solid
    p.source, p.image, p.method = "IMAGE", bpy.data.images.load(str(tmp_path / "ex.png")), "SPECTRAL"
    req = solid_ui.panel_request(p)
    flags = build_parser().parse_args(["solid", "--method", "spectral", "--exemplar", str(tmp_path / "ex.png"),
                                       "--seed", "3", "-o", "x.png"])
    assert req.key() == solid_request(flags).key()
    field = req.spectral_field()
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    ref = np.flipud(SpectralTexture(req).image(128, field))
    assert np.abs(_pixels("Solid Texture Preview") - ref).max() <= 0.5 / 255 + 1e-4
    assert p.periodic_info == "Pattern: none found" and p.gaussian_info == ""   # random pixels: no period
    log = []
    solid_ui.draw_solid_all(Recorder(log), bpy.context)
    props = {a for n, a, t in log if n == "prop"}
    assert {"method", "periodic"} <= props and not {"refine", "gaussian", "rest"} & props
    p.periodic = False      # the Periodic Part box is --no-periodic here too
    flags = build_parser().parse_args(["solid", "--method", "spectral", "--exemplar", str(tmp_path / "ex.png"),
                                       "--seed", "3", "--no-periodic", "-o", "x.png"])
    assert solid_ui.panel_request(p).key() == solid_request(flags).key() != req.key()
    p.periodic = True

    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    obj = bpy.context.active_object
    p.target = "COLOR_ATTRIBUTE"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    me = obj.data
    got = np.empty(len(me.vertices) * 4, np.float32)
    me.color_attributes["Solid Texture"].data.foreach_get("color", got)
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    want = srgb_to_linear(field.evaluate(co.reshape(-1, 3).astype(np.float64) * 2.0))
    np.testing.assert_allclose(got.reshape(-1, 4)[:, :3], want, atol=1e-5)

    p.target = "VOLUME"
    assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
    from omninoise.export.vdb import read_volume

    col = read_volume(str(tmp_path / "Solid_Texture.vdb"), "color", (8, 8, 8))
    c = -1 + (np.arange(8) + 0.5) * 0.25            # voxel centres of the sphere's local bounds [-1, 1]^3
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    want = srgb_to_linear(field.evaluate(np.stack([x, y, z], -1).reshape(-1, 3) * 2.0))
    np.testing.assert_allclose(col.reshape(-1, 3), want, atol=5e-5)     # the grid's points in its own arithmetic


def test_a_photo_in_an_exr_is_the_same_photo_in_blender_and_on_the_command_line(scene, tmp_path):
    """A float image holds scene-linear colour: the panel encodes it to sRGB, and the command line reads the same
    file to the same pixels, so both make the same request."""
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.cli.main import build_parser
    from omninoise.cli.solid import solid_request
    from omninoise.export.images import read_rgb, write_exr

    rgb = np.random.default_rng(4).integers(0, 256, (64, 72, 3)).astype(np.float32) / 255
    path = str(tmp_path / "ex.exr")
    write_exr(path, srgb_to_linear(rgb))
    ima = bpy.data.images.load(path)
    assert ima.is_float
    assert np.array_equal(common.image_srgb(ima, "image"), read_rgb(path))
    assert np.abs(read_rgb(path) - rgb).max() < 1e-5
    p = scene.omninoise_solid
    p.source, p.image, p.method, p.seed = "IMAGE", ima, "SPECTRAL", 3
    flags = build_parser().parse_args(["solid", "--method", "spectral", "--exemplar", path, "--seed", "3",
                                       "-o", "x.png"])
    assert solid_ui.panel_request(p).key() == solid_request(flags).key()


def test_image_source_is_encoded_by_the_space_model(scene):
    p = scene.omninoise_solid
    ima = bpy.data.images.new("Exemplar", 160, 140, alpha=False)
    rgba = np.ones((140, 160, 4), np.float32)
    rgba[..., :3] = np.random.default_rng(1).random((140, 160, 3))
    ima.pixels.foreach_set(rgba.ravel())
    p.source, p.image = "IMAGE", ima
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    got = _pixels("Solid Texture Preview")
    m = _model("space")
    pixels = np.flipud(np.round(rgba[..., :3] * 255) / 255)
    code = photo_code(m, pixels).code                          # the panel's code: the pipeline's stages
    ref = np.flipud(m.image(128, code, seed=3))
    assert np.abs(got - ref).max() <= 0.5 / 255 + 1e-4
    assert p.periodic_info == "Pattern: none found"      # random pixels have no period
    assert p.gaussian_info == solid_ui.gaussian_info(code) and p.gaussian_info.startswith("Fine detail: ")


def test_the_preview_shows_the_periodic_part_it_found(scene):
    """A brick photo's courses and joints (backend/solid/harmonic.py): the preview shows them, the panel says how
    much of the photo they carry, and the Periodic Part box leaves them out."""
    from omninoise.export.images import read_rgb

    path = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
    p = scene.omninoise_solid
    p.source, p.image, p.seed = "IMAGE", bpy.data.images.load(path), 0
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    assert p.periodic_info == "Pattern: 73 waves, 85 % of the variance"
    log = []
    solid_ui.draw_solid_all(Recorder(log), bpy.context)
    assert ("label", None, p.periodic_info) in [(n, None, t) for n, a, t in log]
    lum = read_rgb(path)[:128, :128].mean(2).ravel()
    with_part = np.flipud(_pixels("Solid Texture Preview")).mean(2).ravel()
    p.periodic = False
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    without = np.flipud(_pixels("Solid Texture Preview")).mean(2).ravel()
    assert np.corrcoef(with_part, lum)[0, 1] > 0.5 > 0.2 > abs(np.corrcoef(without, lum)[0, 1])
    p.periodic = True


def _stripes_image(name="Stripes", period=16, size=128):
    """An image datablock of vertical stripes ``period`` px apart (brightness changes across columns only)."""
    x = np.arange(size)
    rgb = np.zeros((size, size, 3), np.float32)
    rgb[:] = (0.2 + 0.6 * (x % period < period // 2))[None, :, None] * np.array([1.0, 0.8, 0.5], np.float32)
    ima = bpy.data.images.new(name, size, size, alpha=False)
    rgba = np.ones((size, size, 4), np.float32)
    rgba[..., :3] = np.flipud(rgb)
    ima.pixels.foreach_set(rgba.ravel())
    return ima


def test_tileable_image_is_the_requests_synthesis(scene, tmp_path):
    """Tileable Image (backend/solid/synthesis.py) stores the tile the command line's request synthesises from the
    same pixels, 8-bit, row 0 at the bottom, and the panel draws it for an image exemplar; without one it says
    what to pick."""
    from omninoise.backend.solid.request import SolidRequest

    p = scene.omninoise_solid
    with pytest.raises(RuntimeError, match="set Source to Image"):
        bpy.ops.omninoise.solid_tileable()
    ima = _stripes_image()
    p.source, p.image, p.tile, p.seed = "IMAGE", ima, 64, 5
    assert bpy.ops.omninoise.solid_tileable() == {"FINISHED"}
    got = _pixels("Solid Texture Tile")
    ref = SolidRequest(exemplar=common.image_srgb(ima, "image"), seed=5, method="synthesis",
                       tile=64).synthesis_field().tile
    assert got.shape == (64, 64, 3) and np.abs(got - ref).max() <= 0.5 / 255 + 1e-4
    g = got.mean(2)      # the stripes stay vertical: brightness changes across columns, not down them
    assert np.abs(np.diff(g, axis=1)).mean() > 10.0 * np.abs(np.diff(g, axis=0)).mean()
    log = []
    solid_ui.draw_solid_all(Recorder(log), bpy.context)
    assert "Make Tileable Image" in [t for n, a, t in log if n == "operator"] and "tile" in [a for n, a, t in log]


def test_the_tile_is_box_projected_onto_a_mesh_without_uvs_at_the_photos_scale(scene, tmp_path):
    """Project Tile onto Object: a cube without UVs renders (Cycles) the tile's stripes upright on its front face at
    the photo's pixel scale times Scale (4 repeats of a 64 px tile per Blender unit at Scale 2: 32 stripe periods
    across a 2 unit face); the nodes are reused when it runs again; errors say what is missing."""
    p = scene.omninoise_solid
    with pytest.raises(RuntimeError, match="object: select a mesh to project the tile onto"):
        bpy.ops.omninoise.solid_tile_material()
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object
    while cube.data.uv_layers:
        cube.data.uv_layers.remove(cube.data.uv_layers[0])
    with pytest.raises(RuntimeError, match="tile: no tileable image 'Solid Texture Tile' yet: make one with Make "
                                           "Tileable Image first"):
        bpy.ops.omninoise.solid_tile_material()
    p.source, p.image, p.tile, p.seed, p.scale = "IMAGE", _stripes_image(), 64, 5, 2.0
    assert bpy.ops.omninoise.solid_tileable() == {"FINISHED"}
    bpy.context.view_layer.objects.active = cube
    assert bpy.ops.omninoise.solid_tile_material() == {"FINISHED"}
    assert bpy.ops.omninoise.solid_tile_material() == {"FINISHED"}       # again: the same nodes
    nt = cube.active_material.node_tree
    images = [n for n in nt.nodes if n.type == "TEX_IMAGE"]
    assert len(images) == 1 and images[0].image == bpy.data.images["Solid Texture Tile"]
    assert images[0].projection == "BOX" and images[0].inputs["Vector"].links[0].from_node.type == "MAPPING"
    assert tuple(nt.nodes["OmniNoise Tile Scale"].inputs["Scale"].default_value) == pytest.approx((4.0,) * 3)
    assert solid_ui.tile_repeats(2.0, 64) == pytest.approx(4.0)
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    assert bsdf.inputs["Base Color"].links[0].from_node == images[0]

    scene.render.engine = "CYCLES"
    scene.cycles.samples, scene.cycles.use_denoising = 1, False
    scene.render.resolution_x = scene.render.resolution_y = 128
    scene.render.resolution_percentage = 100
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    cam.data.type, cam.data.ortho_scale = "ORTHO", 2.0
    cam.location, cam.rotation_euler = (0.0, -10.0, 0.0), (np.pi / 2, 0.0, 0.0)     # facing the -Y face
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.rotation_euler = (np.pi / 2, 0.0, 0.0)
    for o in (cam, sun):
        scene.collection.objects.link(o)
    scene.camera = cam
    scene.render.filepath = str(tmp_path / "front.png")
    bpy.ops.render.render(write_still=True)
    shot = bpy.data.images.load(scene.render.filepath)
    px = np.empty(128 * 128 * shot.channels, np.float32)
    shot.pixels.foreach_get(px)
    g = px.reshape(128, 128, shot.channels)[8:-8, 8:-8, :3].mean(2)
    assert g.mean() > 0.05                                       # lit, not black
    cols = np.abs(np.fft.rfft(g.mean(0) - g.mean()))             # brightness across the face, 112 px
    assert abs(int(np.argmax(cols)) - 32 * 112 / 128) <= 1.5     # 32 periods per 128 px: the photo's scale x 2
    assert np.abs(np.diff(g, axis=0)).mean() < 0.25 * np.abs(np.diff(g, axis=1)).mean()   # upright: vertical stripes
    p.coords = "WORLD"
    assert bpy.ops.omninoise.solid_tile_material() == {"FINISHED"}
    assert nt.nodes["OmniNoise Tile Scale"].inputs["Vector"].links[0].from_node.type == "NEW_GEOMETRY"
    p.coords = "OBJECT"
    assert bpy.ops.omninoise.solid_tile_material() == {"FINISHED"}
    assert nt.nodes["OmniNoise Tile Scale"].inputs["Vector"].links[0].from_node.type == "TEX_COORD"
    assert len(nt.nodes) == 5      # output, BSDF, image, mapping, positions: nothing left over from switching


def test_errors_are_reported(scene):
    p = scene.omninoise_solid
    with pytest.raises(RuntimeError, match="select an object"):
        bpy.ops.omninoise.solid_bake()
    bpy.ops.mesh.primitive_plane_add()
    me = bpy.context.active_object.data
    me.uv_layers.remove(me.uv_layers[0])
    me.update()
    with pytest.raises(RuntimeError, match="has no UV map"):
        bpy.ops.omninoise.solid_bake()
    p.source = "IMAGE"
    with pytest.raises(RuntimeError, match="pick an exemplar image"):
        bpy.ops.omninoise.solid_preview()
    p.source, p.target = "SHIPPED", "VOLUME"
    bpy.ops.object.empty_add()      # nothing to fill: refused before any work, nothing written
    before = set(os.listdir(p.folder))
    with pytest.raises(RuntimeError, match=r"'Empty' has no extent to fill with a volume"):
        bpy.ops.omninoise.solid_bake()
    assert set(os.listdir(p.folder)) == before


def test_a_partly_transparent_exemplar_is_refused_unless_its_alpha_is_ignored(scene):
    """What lies under a cutout's transparent pixels is no colour of the photo: refused, naming the image, unless
    the image's Alpha is set to None (then its RGB is the photo)."""
    p = scene.omninoise_solid
    ima = _stripes_image("Cutout")
    rgba = np.empty(128 * 128 * 4, np.float32)
    ima.pixels.foreach_get(rgba)
    rgba = rgba.reshape(128, 128, 4)
    rgba[:32, :, 3] = 0.0
    ima.pixels.foreach_set(rgba.ravel())
    p.source, p.image = "IMAGE", ima
    with pytest.raises(RuntimeError, match=r"image 'Cutout'.*partly transparent \(alpha below 1 on 25 %"):
        bpy.ops.omninoise.solid_preview()
    ima.alpha_mode = "NONE"
    assert common.image_srgb(ima, "image").shape == (128, 128, 3)
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}


def test_an_image_a_method_cannot_use_is_named_as_the_panel_names_it(scene):
    """The request's exemplar is the panel's Image: a photo too small for any method or for the method, and a
    float image holding NaN, are reported as the image's errors, before and while the work runs."""
    p = scene.omninoise_solid
    p.source, p.image = "IMAGE", bpy.data.images.new("Line", 64, 1)
    for method in ("NEURAL", "SPECTRAL"):
        p.method = method
        with pytest.raises(RuntimeError, match=r"image: the photo is 64 x 1 px; a texture is read from a photo of "
                                               r"at least 16 px a side"):
            bpy.ops.omninoise.solid_preview()
    p.image = bpy.data.images.new("Small", 24, 24)
    with pytest.raises(RuntimeError, match=r"image: the photo is 24 x 24 px; a spectral solid needs at least 32"):
        bpy.ops.omninoise.solid_preview()
    p.method = "NEURAL"
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}        # the neural texture reads it
    bad = bpy.data.images.new("Bad", 32, 32, float_buffer=True)
    bad.pixels.foreach_set(np.full(32 * 32 * 4, np.nan, np.float32))
    p.image = bad
    with pytest.raises(RuntimeError, match="image: image 'Bad' holds NaN or infinite values"):
        bpy.ops.omninoise.solid_preview()
    scene.render.engine, scene.render.resolution_x, scene.render.resolution_y = "BLENDER_WORKBENCH", 16, 16
    bpy.ops.object.camera_add()
    scene.camera = bpy.context.active_object
    bpy.ops.render.render()                 # the Render Result: an image an artist can pick, whose pixels are hidden
    p.image = bpy.data.images["Render Result"]
    with pytest.raises(RuntimeError, match=r"image: image 'Render Result' is Blender's render view, whose pixels "
                                           r"scripts cannot read: save it \(Image > Save As\)"):
        bpy.ops.omninoise.solid_preview()


def test_worker_bake_cancels_and_leaves_nothing(scene):
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    p = scene.omninoise_solid
    p.size = 1024
    op = solid_ui.OMNINOISE_OT_solid_bake
    task = op._start(type("Op", (), {"report": lambda *a: None, "_start_target": op._start_target})(),
                     bpy.context, False)
    assert task.progressed.wait(120)  # the first step is done; no spinning
    task.cancel()
    tasks.wait(task)
    assert task.status == "cancelled" and task.progress < 0.9 and "Solid Texture" not in bpy.data.images
    assert bpy.context.active_object.active_material is None


def test_a_photo_preview_shows_its_encoding_and_stops_when_cancelled(scene, monkeypatch):
    """The neural texture of a photo is encoded on the worker with progress (its stages and the Gaussian rest's
    check, about 2.5 s) in the first part of the preview's bar, and Esc stops the encoding: no preview, nothing
    remembered, and the next preview encodes it whole."""
    path = os.path.join(ROOT, "data", "photos", "val", "rock__rock_grey.jpg")
    p = scene.omninoise_solid
    p.source, p.image, p.method = "IMAGE", bpy.data.images.load(path), "NEURAL"
    op = solid_ui.OMNINOISE_OT_solid_preview
    task = op._start(type("Op", (), {})(), bpy.context, False)
    assert task.progressed.wait(120)        # the encoding's first stage is done: its check has not begun
    task.cancel()
    tasks.wait(task)
    assert task.status == "cancelled" and task.progress < 0.8 and f"{p.name} Preview" not in bpy.data.images
    seen, report = [], tasks.Task._report
    monkeypatch.setattr(tasks.Task, "_report", lambda self, f: seen.append(f) or report(self, f))
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    assert len([f for f in seen if 0 < f < 0.8]) >= 10, seen
    assert seen == sorted(seen) and seen[-1] == 1.0 and f"{p.name} Preview" in bpy.data.images


def test_panel_draws(scene):
    log = []
    solid_ui.draw_solid_all(Recorder(log), bpy.context)
    props = [a for n, a, t in log if n == "prop"]
    assert {"source", "texture", "scale", "seed", "coords", "target", "size", "margin", "name"} <= set(props)
    assert [t for n, a, t in log if n == "operator"] == ["Preview", "Bake", ""]     # and Save as Job File's icon


def test_the_panel_builds_the_command_lines_request(scene, tmp_path):
    """The panel, the command line and job files build one request (backend.solid.request): equal settings give
    equal keys, an image datablock's pixels count as the file they came from."""
    from omninoise.backend.sources import solid_request_from_dict
    from omninoise.cli.main import build_parser
    from omninoise.cli.solid import solid_request
    from omninoise.export.images import write_png

    p = scene.omninoise_solid
    space = os.path.join(solid_ui.models_dir(), "space")

    def flags(*args):
        return solid_request(build_parser().parse_args(["solid", *args, "--seed", "3", "-o", "x.png"]))

    p.texture = "single:gravel_3d"
    gravel = os.path.join(solid_ui.models_dir(), "gravel_3d")
    assert solid_ui.panel_request(p).key() == flags("--model", gravel).key() == \
        solid_request_from_dict({"model": gravel, "seed": 3}).key()
    p.texture = "space:space:grass"
    assert solid_ui.panel_request(p).key() == flags("--model", space, "--exemplar", "grass").key()
    rgb = np.random.default_rng(2).integers(0, 256, (40, 48, 3)).astype(np.uint8)
    write_png(str(tmp_path / "ex.png"), rgb)
    ima = bpy.data.images.load(str(tmp_path / "ex.png"))
    p.source, p.image, p.refine = "IMAGE", ima, 4
    req = solid_ui.panel_request(p)
    assert req.key() == flags("--model", space, "--exemplar", str(tmp_path / "ex.png"), "--refine", "4").key()
    assert req.key() == solid_request_from_dict({"model": space, "exemplar": str(tmp_path / "ex.png"), "refine": 4,
                                                 "seed": 3}).key()
    p.periodic = False     # the Periodic Part box is --no-periodic and a job file's periodic = false
    req = solid_ui.panel_request(p)
    assert req.key() == flags("--model", space, "--exemplar", str(tmp_path / "ex.png"), "--refine", "4",
                              "--no-periodic").key()
    assert req.key() == solid_request_from_dict({"model": space, "exemplar": str(tmp_path / "ex.png"), "refine": 4,
                                                 "seed": 3, "periodic": False}).key()
    p.periodic, p.gaussian = True, False     # the Gaussian Rest box is --no-gaussian and gaussian = false
    req = solid_ui.panel_request(p)
    assert req.key() == flags("--model", space, "--exemplar", str(tmp_path / "ex.png"), "--refine", "4",
                              "--no-gaussian").key()
    assert req.key() == solid_request_from_dict({"model": space, "exemplar": str(tmp_path / "ex.png"), "refine": 4,
                                                 "seed": 3, "gaussian": False}).key()
    p.gaussian, p.rest = True, "upright"     # the Rest Kind menu is --rest and a job file's rest
    req = solid_ui.panel_request(p)
    assert req.rest == "upright"
    assert req.key() == flags("--model", space, "--exemplar", str(tmp_path / "ex.png"), "--refine", "4",
                              "--rest", "upright").key()
    assert req.key() == solid_request_from_dict({"model": space, "exemplar": str(tmp_path / "ex.png"), "refine": 4,
                                                 "seed": 3, "rest": "upright"}).key()
    p.rest = "auto"
    # Tileable Image is --method synthesis and a job file's method = "synthesis"
    p.tile = 64
    req = solid_ui.tile_request(p)
    assert req.key() == flags("--method", "synthesis", "--exemplar", str(tmp_path / "ex.png"), "--tile", "64").key()
    assert req.key() == solid_request_from_dict({"method": "synthesis", "exemplar": str(tmp_path / "ex.png"),
                                                 "tile": 64, "seed": 3}).key()


def test_a_models_folder_that_is_no_folder_is_said_in_the_texture_menu_and_by_the_operators(scene, monkeypatch,
                                                                                           tmp_path):
    """OMNINOISE_MODELS naming no folder: the Texture menu's one item says so (the menu's callback must not
    raise while Blender draws it), and the operators refuse in one line naming the variable."""
    monkeypatch.setattr(solid_ui, "MODELS_DIR", None)
    monkeypatch.setenv("OMNINOISE_MODELS", str(tmp_path / "gone"))
    said = f"OMNINOISE_MODELS: {tmp_path / 'gone'} is not a folder"
    items = solid_ui._texture_items(None, bpy.context)
    assert len(items) == 1 and items[0][0] == "NONE" and items[0][2].startswith(said)
    bpy.ops.mesh.primitive_cube_add()
    with pytest.raises(RuntimeError, match=said):
        bpy.ops.omninoise.solid_preview()


@pytest.mark.parametrize("channels", [1, 3, 4])
def test_a_16_bit_photo_is_read_as_the_command_line_reads_its_file(scene, tmp_path, channels):
    """Blender reads a 16-bit PNG into floats, linearised from its colour space (or left as stored where that is
    Non-Color): the panels read the file's own values, as the command line does, to the bit, so a bake and the job
    saved from it share one key (the Neural Noise panel's Fit to Image reads it so too); a painted image is read as
    Blender holds it (sRGB's inverse, within 1e-5), and one whose colour space makes another picture of the file
    (Linear) as Blender shows it."""
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.export import read_rgb
    from omninoise.export.images import linear_to_srgb, read_image, write_png

    rng = np.random.default_rng(channels)
    v = rng.integers(0, 65536, (40, 56, channels)).astype(np.uint16)
    if channels == 4:
        v[..., 3] = 65535
    path = str(tmp_path / f"photo{channels}.png")
    write_png(path, v[..., 0] if channels == 1 else v)
    want = read_rgb(path)
    p = scene.omninoise_solid
    p.source, p.method = "IMAGE", "SPECTRAL"
    for space in ("sRGB", "Non-Color"):
        ima = bpy.data.images.load(path, check_existing=False)
        ima.colorspace_settings.name = space
        assert ima.is_float
        np.testing.assert_array_equal(common.image_srgb(ima, "image"), want, err_msg=space)
        np.testing.assert_allclose(common.image_colours(ima, "fit image").mean(axis=2), read_image(path), atol=1e-7)
        p.image = ima
        assert solid_ui.panel_request(p).key() == SolidRequest(exemplar=path, method="spectral", seed=3).check().key()
    ima = bpy.data.images.load(path, check_existing=False)
    px = np.empty(len(ima.pixels), np.float32)
    ima.pixels.foreach_get(px)
    ima.pixels.foreach_set(px)                        # painted: Blender's pixels are read
    assert ima.is_dirty
    got = common.image_srgb(ima, "image")
    assert 0 < np.abs(got - want).max() < 2e-5
    ima = bpy.data.images.load(path, check_existing=False)
    ima.colorspace_settings.name = "Linear Rec.709"     # the file's values taken as linear: a brighter picture
    raw = np.flipud(np.asarray(ima.pixels[:], np.float32).reshape(40, 56, -1))[..., :3]
    np.testing.assert_allclose(common.image_srgb(ima, "image"), linear_to_srgb(raw), atol=1e-6)


def test_a_float_image_past_white_or_under_black_is_reported(scene, capfd, monkeypatch):
    """A float Image is read as colours in [0, 1]: where 1 % or more of it is past white or under black, the
    operator reports it as a warning (Blender's default view, AgX, shows values above 1 as bright colours, not as
    the white they are read as), as the command line's notes say; an 8-bit image and one within [0, 1] are not."""
    p = scene.omninoise_solid
    rgba = np.ones((64, 64, 4), np.float32)
    rgba[..., :3] = 0.4
    rgba[:16, :, :3] = 4.5                                      # a quarter past white
    rgba[16:24, :, 2] = -0.2                                    # an eighth under black
    hdr = bpy.data.images.new("HDR", 64, 64, float_buffer=True)
    hdr.pixels.foreach_set(np.clip(rgba, 0.0, 1.0).ravel())
    common.image_srgb(hdr, "image")                 # a read before the pixels change is not what the notes measure
    hdr.pixels.foreach_set(rgba.ravel())
    assert common.image_clipped_notes(hdr) == [
        "25 % of the photo's pixels are brighter than white (above 1) and are read as white; lower its exposure to "
        "keep their colours",
        "12.5 % of the photo's pixels are darker than black (below 0) and are read as black; raise or offset its "
        "values into [0, 1] to keep their colours"]
    p.source, p.method, p.image = "IMAGE", "NEURAL", hdr
    capfd.readouterr()
    reads, read = [], common.image_pixels
    monkeypatch.setattr(common, "image_pixels", lambda ima, setting: reads.append(ima.name) or read(ima, setting))
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    assert reads == ["HDR"]             # the warning's shares come from the request's own read of the pixels
    out = capfd.readouterr()
    said = out.out + out.err
    assert "Image 'HDR': 25 % of the photo's pixels are brighter than white" in said, said
    assert "Image 'HDR': 12.5 % of the photo's pixels are darker than black" in said, said
    rgba[..., :3] = np.clip(rgba[..., :3], 0.0, 1.0)
    hdr.pixels.foreach_set(rgba.ravel())
    assert common.image_clipped_notes(hdr) == [] and common.image_clipped_notes(_stripes_image()) == []
    p.image = _stripes_image()
    assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
    out = capfd.readouterr()
    assert "Image '" not in out.out + out.err
