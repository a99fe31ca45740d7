"""Neural noise in Blender (Maesumi et al. 2024): swatches, a painted blend map, a background bake.

Settings live on the scene (``Scene.omninoise_neural``) and are saved with the
.blend.  A swatch is a noise class with its parameters (shown under the class's
own parameter names) and a colour; the blend map is an image painted in those
colours with Blender's texture-paint tools.  The bake builds the conditioning
grid on the main thread, denoises on a :mod:`.tasks` worker (progress per DDIM
step, Esc / Cancel stop within one step) and stores the result as an image
datablock, optionally wired into the active material as Non-Color data.  The sequence bake animates the
conditioning between keyframes (the swatches spread over a frame range, or a TOML keyframe file), writes one
file per frame and loads them as one image sequence on the Image Texture node.
"""
from __future__ import annotations

import os

import bpy
from bl_operators.presets import AddPresetBase
from bl_ui.utils import PresetPanel
import numpy as np
from bpy.props import BoolProperty, CollectionProperty, EnumProperty, FloatProperty, FloatVectorProperty, \
    IntProperty, PointerProperty, StringProperty

from . import tasks
from .. import backend
from .bake_ui import SaveJobOperator, draw_progress
from .presets import NEURAL_VALUES, SUBDIRS
from .common import Sidebar, backend_module as _mod, image_colours, image_pixels, neural_model_folder
from .tasks import TaskOperator
from .preferences import precision, threads

__all__ = ["model", "panel_request", "build_conditioning", "sequence_keys", "job_spec", "thumbnail_name", "attach",
           "detach"]

_MODEL = {}
N_PARAMS = 4


_SAMPLERS = _mod("neural.sampler")  # numpy only: cheap at register time
DEFAULT_SAMPLER, DEFAULT_STEPS = _SAMPLERS.DEFAULT_SAMPLER, _SAMPLERS.DEFAULT_STEPS
#: the samplers of backend.neural.sampler, as the panel lists them
SAMPLER_ITEMS = [("dpmpp_2m", "DPM-Solver++(2M)", "Second-order multistep: the fewest steps for a clean image"),
                 ("ddim", "DDIM", "First order: needs more steps for the same detail (about 30)"),
                 ("heun", "Heun", "Second order, two model evaluations per step")]


def model():
    """The shipped model, loaded on first use (never at register time), with onnxruntime on the
    preferences' CPU threads and precision (a changed preference loads the model again)."""
    key = (threads(), precision())
    if _MODEL.get("key") != key:
        _MODEL.clear()
        _MODEL.update(key=key, m=_mod("neural.model").NeuralNoiseModel(neural_model_folder(), threads=key[0],
                                                                        precision=key[1]))
    return _MODEL["m"]


def _class_items(self, context):
    try:
        names = model().config["trained_classes"]
    except Exception as exc:  # a missing or altered model: one item that says so
        return [("NONE", "No model", str(exc))]
    return [(n, n.replace("_", " ").title(), model().class_params[n]["doc"]) for n in names]


def _reset_params(self, context) -> None:
    try:
        spec = model().class_params[self.noise]["params"]
    except Exception:
        return
    for i, p in enumerate(spec[:N_PARAMS]):
        setattr(self, f"p{i}", 0.5 * (p["min"] + p["max"]))


class OMNINOISE_PG_swatch(bpy.types.PropertyGroup):
    noise: EnumProperty(name="Noise", items=_class_items, update=_reset_params,
                        description="The kind of noise this swatch draws (choosing one resets its parameters)")
    p0: FloatProperty(name="Parameter 1", description="The noise class's first parameter (named in the panel); "
                                                       "a value outside the class's range is refused at bake")
    p1: FloatProperty(name="Parameter 2", description="The noise class's second parameter (named in the panel)")
    p2: FloatProperty(name="Parameter 3", description="The noise class's third parameter (named in the panel)")
    p3: FloatProperty(name="Parameter 4", description="The noise class's fourth parameter (named in the panel)")
    color: FloatVectorProperty(name="Color", subtype="COLOR", size=3, min=0.0, max=1.0, default=(1.0, 0.0, 0.0),
                               description="The color that paints this swatch into the blend map")

    def spec(self) -> tuple:
        params = model().class_params[self.noise]["params"][:N_PARAMS]
        return self.noise, {p["name"]: float(getattr(self, f"p{i}")) for i, p in enumerate(params)}


_PALETTE = [(1, 0, 0), (0, 0, 1), (0, 1, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 1), (0, 0, 0)]


class OMNINOISE_PG_neural(bpy.types.PropertyGroup):
    swatches: CollectionProperty(type=OMNINOISE_PG_swatch, name="Swatches",
                                 description="The noises to draw or blend, each with its parameters and paint color")
    active: IntProperty(default=0, name="Active Swatch", description="The swatch shown and edited below the list")
    mode: EnumProperty(name="Layout", description="How the swatches share the image", items=[
        ("SINGLE", "Single", "The active swatch everywhere"),
        ("GRADIENT", "Left to Right", "The first swatch on the left blending into the second on the right"),
        ("CORNERS", "Four Corners", "Swatches 1 to 4 at the corners, blended across the image"),
        ("MAP", "Painted Map", "Each pixel of the blend map takes the swatch of its color")], default="SINGLE")
    blend_map: PointerProperty(name="Blend Map", type=bpy.types.Image,
                               description="An image painted in the swatches' colors: each pixel takes the swatch "
                                           "of its color")
    width: FloatProperty(name="Transition", description="Width of painted transitions, pixels", default=32.0,
                         min=1.0, soft_max=256.0)
    sharpness: FloatProperty(name="Sharpness", description="Transition exponent (1 = linear)", default=1.0,
                             min=0.1, soft_max=8.0)
    size: IntProperty(name="Size", default=512, min=8, soft_max=4096, max=16384,
                      description="Width and height of the baked image in pixels (time and memory grow with its "
                                  "area)")
    sampler: EnumProperty(name="Sampler", items=SAMPLER_ITEMS, default=DEFAULT_SAMPLER,
                          description="How the image is denoised; DPM-Solver++(2M) needs the fewest steps")
    steps: IntProperty(name="Steps", default=DEFAULT_STEPS, min=2, max=1000,
                       description="Sampler timesteps (model evaluations: the same, twice for Heun)")
    seed: IntProperty(name="Seed", default=0, min=0, description="Another seed draws another image of the same noise")
    tileable: BoolProperty(name="Tileable", description="Seamless tile (the size becomes a multiple of 8)")
    depth: EnumProperty(name="Depth", items=[("8", "8-bit", "256 levels: small, may band in smooth gradients"),
                                             ("16", "16-bit Half", "Half floats: smooth gradients at half the size"),
                                             ("32", "32-bit Float", "Full float precision")],
                        default="32", description="Precision of the stored image")
    name: StringProperty(name="Name", default="Neural Noise", description="Name of the image (and of saved files)")
    save: EnumProperty(name="Save", description="Keep the image inside the .blend only, or also write a file", items=[("NONE", "Pack Only", "Keep the image packed in the .blend"),
                                           ("EXR", "OpenEXR", "Also write an EXR (half for 16-bit, float for 32-bit)"),
                                           ("PNG", "PNG", "Also write an 8-bit PNG")], default="NONE")
    folder: StringProperty(name="Folder", subtype="DIR_PATH", default="//omninoise/",
                           description="Where saved images go ('//' = beside the .blend, or the cache folder)")
    add_node: BoolProperty(name="Add Image Texture Node", default=True,
                           description="Wire the result into the active material as Non-Color data")
    # animation: an image sequence whose classes and parameters move between keyframes (Fig. 11)
    frame_start: IntProperty(name="Start", default=1, min=0, description="First frame of the sequence")
    frame_end: IntProperty(name="End", default=48, min=0, description="Last frame of the sequence")
    key_source: EnumProperty(name="Keyframes", description="What sets the noise on each keyframe", items=[
        ("SWATCHES", "Swatches", "Swatch 1 on the first frame, the last swatch on the last frame, the others "
                                 "evenly between (swatch i uses seed + i)"),
        ("FILE", "Keyframe File", "A TOML keyframe file, as the command line's --keys")], default="SWATCHES")
    keys_file: StringProperty(name="Keyframe File", subtype="FILE_PATH",
                              description="A TOML file of keys, each with a frame, a noise, its parameters and a seed "
                                          "(the format of `omninoise neural --keys`)")
    latent: EnumProperty(name="Motion", description="How the noise's random start moves from frame to frame", items=[
        ("fixed", "Fixed", "One initial latent for every frame: only the classes and parameters move"),
        ("slerp", "Between Seeds", "The latent moves along the sphere between the keyframes' seeds"),
        ("drift", "Drift", "The latent circles at a constant speed, so the noise flows even between keys")],
        default="fixed")
    fit_image: PointerProperty(name="Fit Image", type=bpy.types.Image,
                               description="An image to imitate: Fit to Image finds the class, parameters and seed")
    drift: FloatProperty(name="Drift Speed", default=0.05, min=0.0, soft_max=0.5,
                         description="Radians per frame of the drifting latent")


# -- conditioning from the settings (main thread) -----------------------------------------

def panel_request(p: OMNINOISE_PG_neural, size: int, steps: int | None = None):
    """The :class:`backend.neural.request.NeuralRequest` of the scene's settings at ``size``² (checked);
    SettingError naming what is wrong."""
    R = _mod("neural.request")
    m = model()
    sw = list(p.swatches)
    if not sw:
        raise backend.SettingError("swatches", "add a swatch first")
    kw = dict(width=size, height=size, transition=p.width, sharpness=p.sharpness, seed=p.seed,
              steps=p.steps if steps is None else steps, sampler=p.sampler, tileable=p.tileable)
    if p.mode == "SINGLE":
        return R.NeuralRequest("uniform", [sw[min(p.active, len(sw) - 1)].spec()], **kw).check(m)
    if p.mode == "GRADIENT":
        if len(sw) < 2:
            raise backend.SettingError("swatches", "a left-to-right blend needs two swatches")
        return R.NeuralRequest("gradient", [sw[0].spec(), sw[1].spec()], **kw).check(m)
    if p.mode == "CORNERS":
        if len(sw) < 4:
            raise backend.SettingError("swatches", "a four-corner blend needs four swatches")
        return R.NeuralRequest("corners", [s.spec() for s in sw[:4]], **kw).check(m)
    img = p.blend_map
    if img is None:
        raise backend.SettingError("blend map", "pick or create a blend map image")
    iw, ih = img.size
    if iw != ih:
        raise backend.SettingError("blend map", f"the map is {iw}x{ih}; it must be square like the output")
    px = image_pixels(img, "blend map")     # a map's colours name its regions; what alpha a brush left is not read
    rgb = px[..., :3] if px.shape[2] >= 3 else np.repeat(px[..., :1], 3, axis=2)
    # a map larger than the output is read at the output's size (a 4096 px map classified whole takes 7 s, here on
    # the main thread); a smaller one the request draws at that size; the transitions stay in the map's pixels
    rgb, grow = R.map_at(rgb, min(size, ih), min(size, iw))
    kw["transition"] = p.width * grow
    # brush strokes blend colours at their edges: each pixel takes its nearest swatch colour
    regions = R.regions_from_colours(rgb, [tuple(s.color) for s in sw], tolerance=0.2, where="blend map")
    return R.NeuralRequest("painted", [s.spec() for s in sw], regions=regions, **kw).check(m)


def build_conditioning(p: OMNINOISE_PG_neural, size: int):
    """(E + P, H, W) float32 grid for the scene's settings; SettingError naming what is wrong."""
    return panel_request(p, size).conditioning(model())


def _store(name: str, img: np.ndarray, depth: str):
    """A float image datablock holding ``img`` (H, W) in [0, 1] (8/16-bit quantised on request)."""
    H, W = img.shape
    if depth == "8":
        img = np.round(img * 255.0) / 255.0
    elif depth == "16":
        img = img.astype(np.float16).astype(np.float32)
    ima = bpy.data.images.get(name)
    if ima is None or tuple(ima.size) != (W, H):
        if ima is not None:
            bpy.data.images.remove(ima)
        ima = bpy.data.images.new(name, W, H, alpha=False, float_buffer=depth != "8")
    ima.colorspace_settings.name = "Non-Color"  # set before the pixels (changing it regenerates the image)
    rgba = np.ones((H, W, 4), np.float32)
    rgba[..., :3] = np.flipud(img)[..., None]
    ima.pixels.foreach_set(rgba.ravel())
    ima.update()
    ima.pack()
    return ima


class OMNINOISE_OT_neural_bake(TaskOperator, bpy.types.Operator):
    """Bake neural noise from the swatches and the blend layout into an image"""

    bl_idname = "omninoise.neural_bake"
    bl_label = "Bake Neural Noise"
    bl_options = {"REGISTER", "UNDO"}

    preview: BoolProperty(name="Preview", description="A quick 64 px, 10-step preview", default=False,
                          options={"SKIP_SAVE"})

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_neural
        size = 64 if self.preview else _bake_size(p)
        steps = min(p.steps, 10) if self.preview else p.steps
        _mod("neural.generate").check_memory("size", size, size)
        m = model()
        req = panel_request(p, size, steps)
        depth = p.depth
        name = p.name + (" Preview" if self.preview else "")
        spec = None
        if p.save != "NONE" and not self.preview:   # the file a job of this bake writes (Save as Job File)
            spec = _image_spec(p, req)
            maps = [(f"the image {ima.name!r}", bpy.path.abspath(ima.filepath)) for ima in (p.blend_map, p.fit_image)
                    if ima is not None and ima.filepath]
            _mod("bake").check_not_read(spec.output, "name", maps)    # a painted map saved under the bake's name
        save_path = None if spec is None else spec.output
        obj, add_node = context.active_object, p.add_node and not self.preview

        def work(progress, cancel):
            def step(i, n, x0):
                progress((i + 1) / n)
                if cancel():
                    raise backend.Cancelled("cancelled")

            img = _mod("neural.request").generate_request(m, req, callback=step)
            if spec is not None:  # atomic, off the main thread; with its key, up to date for the saved job
                _mod("bake").write_values(spec, None, img[::-1])
            return img

        def done(img):
            ima = _store(name, img, depth)
            if save_path is not None:
                ima["omninoise_file"] = save_path
            if add_node:
                _image_node(obj, ima)

        return tasks.start(tasks.Task(f"Neural {name}", work, done, None, threads()), blocking=blocking)


def sequence_keys(p) -> list:
    """The keyframes of the scene's animation settings (main thread); SettingError naming what is wrong."""
    A = _mod("neural.animate")
    if p.frame_end < p.frame_start:
        raise backend.SettingError("frames", f"the end frame {p.frame_end} is before the start {p.frame_start}")
    if p.key_source == "FILE":
        if not p.keys_file:
            raise backend.SettingError("keyframe file", "pick a keyframe file (.toml)")
        keys = A.read_keys(bpy.path.abspath(p.keys_file))
    else:
        keys = A.even_keys([s.spec() for s in p.swatches], p.frame_start, p.frame_end, p.seed)
    for k in keys:
        model().param_vector(*k.spec)  # unknown classes or parameters fail before the first frame
    return keys


def _image_node(obj, ima):
    """The active material's Image Texture node showing ``ima`` (added if missing), made active; None when the
    object has no node-based material."""
    mat = None if obj is None else obj.active_material
    if mat is None or mat.node_tree is None:
        return None
    nt = mat.node_tree
    node = next((nd for nd in nt.nodes if nd.type == "TEX_IMAGE" and nd.image == ima), None)
    if node is None:
        node = nt.nodes.new("ShaderNodeTexImage")
        node.image = ima
    nt.nodes.active = node
    return node


def _wire_sequence(node, first: int, n: int) -> None:
    """Play the sequence's files first..first+n-1 on scene frames first..first+n-1."""
    u = node.image_user
    u.frame_duration, u.frame_start, u.frame_offset = n, first, first - 1
    u.use_auto_refresh, u.use_cyclic = True, False


class OMNINOISE_OT_neural_bake_sequence(TaskOperator, bpy.types.Operator):
    """Bake animated neural noise (classes and parameters moving between keyframes) into an image sequence
    on disk, loaded as one sequence image"""

    bl_idname = "omninoise.neural_bake_sequence"
    bl_label = "Bake Neural Noise Sequence"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_neural
        size = _bake_size(p)
        _mod("neural.generate").check_memory("size", size, size)
        m = model()                 # its errors, the keys' and the folder's are reported by _begin, in one line
        keys = sequence_keys(p)
        spec = _sequence_spec(p, keys)      # a sequence lives on disk: EXR unless PNG was picked
        pattern = spec.output
        first, last = p.frame_start, p.frame_end
        n = last - first + 1
        kw = dict(latent=p.latent, speed=p.drift, steps=p.steps, sampler=p.sampler, tileable=p.tileable)
        name = p.name + " Sequence"
        obj, add_node = context.active_object, p.add_node
        write_values = _mod("bake").write_values

        def work(progress, cancel):
            finished = []

            def step(i, steps, x0):
                progress((len(finished) + (i + 1) / steps) / n)
                if cancel():
                    raise backend.Cancelled("cancelled")

            for f, img in _mod("neural.animate").animate(m, keys, (first, last), size, size, cancel=cancel,
                                                          callback=step, **kw):
                finished.append(write_values(spec, f, img[::-1]))   # with its key, as the saved job writes it
                task.label = f"Neural sequence: frame {f} ({len(finished)}/{n})"
            return finished

        def done(paths):
            old = bpy.data.images.get(name)
            if old is not None:
                bpy.data.images.remove(old)
            ima = bpy.data.images.load(paths[0], check_existing=False)
            ima.name = name
            ima.source = "SEQUENCE"
            ima.colorspace_settings.name = "Non-Color"
            ima["omninoise_file"] = pattern
            node = _image_node(obj, ima) if add_node else None
            if node is not None:
                _wire_sequence(node, first, n)

        task = tasks.Task(f"Neural sequence ({n} frames)", work, done, None, threads())
        return tasks.start(task, blocking=blocking)


def _bake_size(p) -> int:
    """The side of the panel's bakes: its size, a multiple of 8 for a tileable image."""
    return p.size + (-p.size) % 8 if p.tileable else p.size


def job_spec(context, target: str):
    """The :class:`backend.bake.BakeSpec` of the panel's image bake (``target`` "IMAGE") or its sequence
    ("SEQUENCE"), as the panel sets them: the files the panel writes and a job of them writes again (Save as Job
    File). SettingError naming what is wrong."""
    p = context.scene.omninoise_neural
    if target == "IMAGE":
        return _image_spec(p, panel_request(p, _bake_size(p)))
    return _sequence_spec(p, sequence_keys(p))


def _files(p) -> dict:
    """Where and how the panel's bakes are written: into its folder under its name, EXR (16-bit half unless the
    depth is 32-bit) or PNG as its Save setting says (an image kept in the .blend only: EXR)."""
    from .bake_blender import output_folder

    ext = ".png" if p.save == "PNG" else ".exr"
    size = _bake_size(p)
    return dict(stem=os.path.join(output_folder(p.folder), bpy.path.clean_name(p.name)), ext=ext,
                kw=dict(grid=_mod("sources").BoxGrid((size, size)), half=ext == ".exr" and p.depth != "32"))


def _image_spec(p, req):
    """The image bake's spec: the checked request ``req`` drawn into the panel's file."""
    f = _files(p)
    colours = [tuple(int(round(c * 255)) for c in s.color) for s in p.swatches] if req.layout == "painted" else None
    source = _mod("sources").NeuralSource.from_request(neural_model_folder(), req, colours)
    return _mod("bake").BakeSpec(p.name, source, output=f["stem"] + f["ext"], **f["kw"]).validate()


def _sequence_spec(p, keys: list):
    """The sequence bake's spec: ``keys`` over the panel's frames, one file a frame."""
    f = _files(p)
    source = _mod("sources").NeuralSource(neural_model_folder(), keys[0].noise, keys[0].params, steps=p.steps,
                                          sampler=p.sampler, tileable=p.tileable, keys=keys, latent=p.latent,
                                          drift=p.drift)
    return _mod("bake").BakeSpec(p.name + " Sequence", source, output=f["stem"] + "_####" + f["ext"],
                                 frames=(p.frame_start, p.frame_end), time=float(p.frame_start), time_step=1.0,
                                 **f["kw"]).validate()


class OMNINOISE_OT_neural_save_job(SaveJobOperator, bpy.types.Operator):
    """Save this neural noise bake, as the panel sets it, as a TOML job file that `omninoise bake`, a farm or the
    Batch Job panel bakes again without Blender"""

    bl_idname = "omninoise.neural_save_job"
    bl_label = "Save Neural Bake as Job File"
    settings = "omninoise_neural"

    target: EnumProperty(name="Bake", default="IMAGE", description="Which of the panel's bakes the job holds",
                         items=[("IMAGE", "Image", "The image bake: one EXR or PNG image"),
                                ("SEQUENCE", "Sequence", "The sequence bake: one image a frame")])

    @classmethod
    def description(cls, context, properties):
        what = "image" if properties.target == "IMAGE" else "sequence"
        return (f"Save the panel's {what} bake as a TOML job file (a painted blend map beside it as a PNG), for "
                "`omninoise bake`, a farm or the Batch Job panel to bake the same files without Blender")

    def specs(self, context) -> list:
        return [job_spec(context, self.target)]

    def reads(self, context) -> dict:
        """The blend map's and fit image's files: the painted map the job reads is never written over them."""
        p = context.scene.omninoise_neural
        return {bpy.path.abspath(ima.filepath): "of an image the panel reads" for ima in (p.blend_map, p.fit_image)
                if ima is not None and ima.filepath}


class OMNINOISE_OT_neural_fit(TaskOperator, bpy.types.Operator):
    """Find the noise class, parameters and seed that look like the Fit Image (inverse design), and put them
    into the active swatch"""

    bl_idname = "omninoise.neural_fit"
    bl_label = "Fit Neural Noise to Image"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_neural
        F = _mod("neural.fit")
        m = model()
        if p.fit_image is None:
            raise backend.SettingError("fit image", "pick an image to fit")
        px = image_colours(p.fit_image, "fit image")
        img, notes = F.prepare_target(px if px.shape[2] > 1 else px[..., 0], m.multiple_of, p.fit_image.name)
        try:
            bank = F.load_bank(_mod("paths").fit_bank())
        except _mod("onnx_models").ModelError:
            bank = None
        for note in notes:
            self.report({"INFO"}, note)
        seed = p.seed

        def work(progress, cancel):
            return F.fit(m, img, seed=seed, bank=bank, progress=progress, cancel=cancel)

        def done(res):
            name = max(res.classes, key=res.classes.get)
            if not p.swatches:
                bpy.ops.omninoise.swatch_add()
            sw = p.swatches[min(p.active, len(p.swatches) - 1)]
            sw.noise = name
            spec = m.class_params[name]["params"][:N_PARAMS]
            for i, prm in enumerate(spec):
                setattr(sw, f"p{i}", res.params[name][prm["name"]])
            p.seed = res.seed
            wm = bpy.context.window_manager
            if wm is not None and hasattr(wm, "omninoise_message"):
                wm.omninoise_message = "Fit: " + ", ".join(
                    f"{n} {w:.0%}" for n, w in sorted(res.classes.items(), key=lambda kv: -kv[1]))

        return tasks.start(tasks.Task("Fit to image", work, done, None, threads()), blocking=blocking)


class OMNINOISE_OT_swatch_add(bpy.types.Operator):
    """Add a noise swatch"""

    bl_idname = "omninoise.swatch_add"
    bl_label = "Add Swatch"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    def execute(self, context):
        p = context.scene.omninoise_neural
        sw = p.swatches.add()
        sw.color = _PALETTE[(len(p.swatches) - 1) % len(_PALETTE)]
        items = _class_items(sw, context)
        if items and items[0][0] != "NONE":
            sw.noise = items[(len(p.swatches) - 1) % len(items)][0]
            _reset_params(sw, context)
        p.active = len(p.swatches) - 1
        return {"FINISHED"}


class OMNINOISE_OT_swatch_remove(bpy.types.Operator):
    """Remove the active swatch"""

    bl_idname = "omninoise.swatch_remove"
    bl_label = "Remove Swatch"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    @classmethod
    def poll(cls, context):
        if not context.scene.omninoise_neural.swatches:
            cls.poll_message_set("There is no swatch to remove")
            return False
        return True

    def execute(self, context):
        p = context.scene.omninoise_neural
        p.swatches.remove(p.active)
        p.active = max(0, min(p.active, len(p.swatches) - 1))
        return {"FINISHED"}


class OMNINOISE_OT_blend_map_new(bpy.types.Operator):
    """Create a blend map to paint: the first swatch's color, with the second's on the right half"""

    bl_idname = "omninoise.blend_map_new"
    bl_label = "New Blend Map"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    def execute(self, context):
        p = context.scene.omninoise_neural
        n = min(p.size, 1024)
        img = bpy.data.images.new(f"{p.name} Map", n, n, alpha=False)
        img.colorspace_settings.name = "Non-Color"  # before the pixels: changing it later regenerates the image
        cols = [tuple(s.color) for s in p.swatches] or [(1.0, 0.0, 0.0)]
        rgba = np.ones((n, n, 4), np.float32)
        rgba[..., :3] = cols[0]
        if len(cols) > 1:
            rgba[:, n // 2:, :3] = cols[1]
        img.pixels.foreach_set(rgba.ravel())
        img.update()
        img.pack()  # painted maps travel inside the .blend
        p.blend_map = img
        p.mode = "MAP"
        return {"FINISHED"}


# -- thumbnails: a small sample of each swatch from the model ---------------------------------

THUMB_SIZE, THUMB_STEPS = 32, 10


def thumbnail_name(index: int) -> str:
    return f".OmniNoise Swatch {index + 1}"   # leading dot: hidden from image browsers


class OMNINOISE_OT_swatch_thumbnails(TaskOperator, bpy.types.Operator):
    """Generate a small preview of every swatch with the model (32 px, 10 steps)"""

    bl_idname = "omninoise.swatch_thumbnails"
    bl_label = "Update Thumbnails"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_neural
        m = model()
        C = _mod("neural.conditioning")
        specs = [s.spec() for s in p.swatches]
        conds = [C.uniform(m, spec, THUMB_SIZE, THUMB_SIZE) for spec in specs]
        if not conds:
            self.report({"ERROR"}, "add a swatch first")
            return None
        keys = [repr(spec) for spec in specs]
        todo = [i for i, k in enumerate(keys) if (bpy.data.images.get(thumbnail_name(i)) is None
                                                  or bpy.data.images[thumbnail_name(i)].get("omninoise_spec") != k)]
        seed = p.seed

        def work(progress, cancel):
            out = {}
            for n, i in enumerate(todo):
                if cancel():
                    raise backend.Cancelled("cancelled")
                out[i] = _mod("neural.generate").generate(m, conds[i], seed, THUMB_STEPS)
                progress((n + 1) / max(1, len(todo)))
            return out

        def done(out):
            for i, img in out.items():
                ima = _store(thumbnail_name(i), img, "8")
                ima["omninoise_spec"] = keys[i]
                ima.preview_ensure()

        return tasks.start(tasks.Task("Swatch thumbnails", work, done, None, threads()), blocking=blocking)


class OMNINOISE_UL_swatches(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        row = layout.row(align=True)
        row.prop(item, "color", text="")
        thumb = bpy.data.images.get(thumbnail_name(index))
        if thumb is not None and thumb.preview is not None:
            row.label(text="", icon_value=thumb.preview.icon_id)
        row.label(text=item.noise.replace("_", " ").title())


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _idle_row(layout):
    row = layout.row(align=True)
    row.enabled = tasks.current() is None
    return row


def draw_neural(layout, context) -> None:
    """The Neural Noise panel's body: the swatches, the layout, the size and seed, and the bakes (the other
    settings are in the sub-panels below it, :data:`SECTIONS`)."""
    p = context.scene.omninoise_neural
    draw_progress(layout)
    row = layout.row()
    row.template_list("OMNINOISE_UL_swatches", "", p, "swatches", p, "active", rows=3)
    col = row.column(align=True)
    col.operator(OMNINOISE_OT_swatch_add.bl_idname, icon="ADD", text="")
    col.operator(OMNINOISE_OT_swatch_remove.bl_idname, icon="REMOVE", text="")
    col.separator()
    col.operator(OMNINOISE_OT_swatch_thumbnails.bl_idname, icon="IMAGE_DATA", text="")
    if p.swatches:
        sw = p.swatches[min(p.active, len(p.swatches) - 1)]
        box = _split(layout.box())
        box.prop(sw, "noise")
        box.prop(sw, "color")
        try:
            spec = model().class_params[sw.noise]["params"]
        except Exception as exc:
            box.label(text=str(exc), icon="ERROR")
            spec = []
        for i, prm in enumerate(spec[:N_PARAMS]):
            box.prop(sw, f"p{i}", text=prm["name"].replace("_", " ").title())
    _split(layout)
    layout.prop(p, "mode")
    if p.mode == "MAP":
        row = layout.row(align=True)
        row.prop(p, "blend_map", text="Blend Map")
        row.operator(OMNINOISE_OT_blend_map_new.bl_idname, icon="ADD", text="")
    layout.prop(p, "size")
    layout.prop(p, "seed")
    row = _idle_row(layout)
    row.operator(OMNINOISE_OT_neural_bake.bl_idname, text="Preview", icon="HIDE_OFF").preview = True
    row.operator(OMNINOISE_OT_neural_bake.bl_idname, text="Bake", icon="RENDER_STILL")
    row.operator(OMNINOISE_OT_neural_save_job.bl_idname, text="", icon="EXPORT").target = "IMAGE"


def _draw_transitions(layout, p) -> None:
    layout.prop(p, "width")
    layout.prop(p, "sharpness")


def _draw_sampling(layout, p) -> None:
    layout.prop(p, "sampler")
    layout.prop(p, "steps")
    layout.prop(p, "tileable")


def _draw_output(layout, p) -> None:
    layout.prop(p, "name")
    layout.prop(p, "depth")
    layout.prop(p, "save")
    if p.save != "NONE":
        layout.prop(p, "folder")
    layout.prop(p, "add_node")


def _draw_animation(layout, p) -> None:
    col = layout.column(align=True)
    col.prop(p, "frame_start", text="Frame Start")
    col.prop(p, "frame_end", text="End")
    layout.prop(p, "key_source")
    if p.key_source == "FILE":
        layout.prop(p, "keys_file")
    layout.prop(p, "latent")
    if p.latent == "drift":
        layout.prop(p, "drift")
    row = _idle_row(layout)
    row.operator(OMNINOISE_OT_neural_bake_sequence.bl_idname, text="Bake Sequence", icon="RENDER_ANIMATION")
    row.operator(OMNINOISE_OT_neural_save_job.bl_idname, text="", icon="EXPORT").target = "SEQUENCE"


def _draw_fit(layout, p) -> None:
    layout.prop(p, "fit_image", text="Image")
    _idle_row(layout).operator(OMNINOISE_OT_neural_fit.bl_idname, text="Fit to Image", icon="EYEDROPPER")


#: the Neural Noise panel's sub-panels, closed at first: (name, label, draw(layout, settings), shown when)
SECTIONS = (("transitions", "Transitions", _draw_transitions, lambda p: p.mode != "SINGLE"),
            ("sampling", "Sampling", _draw_sampling, None),
            ("output", "Output", _draw_output, None),
            ("animation", "Animation", _draw_animation, None),
            ("fit", "Fit to Image", _draw_fit, None))


def draw_neural_all(layout, context) -> None:
    """The panel and every sub-panel in one layout (scripts and tests that look at everything the panel offers)."""
    draw_neural(layout, context)
    p = context.scene.omninoise_neural
    for _, _, draw, shown in SECTIONS:
        if shown is None or shown(p):
            draw(_split(layout), p)


def _panels(space: str, prefix: str, poll=None) -> tuple:
    """The Neural Noise panel and its sub-panels for one editor (the Image Editor's and the Shader Editor's
    sidebars show the same settings)."""
    def parent_draw(self, context):
        draw_neural(self.layout, context)

    def header_preset(self, context):
        OMNINOISE_PT_neural_presets.draw_panel_header(self.layout)

    parent_id = f"OMNINOISE_PT_neural_{prefix}"
    ns = dict(bl_label="Neural Noise", bl_space_type=space, draw=parent_draw, draw_header_preset=header_preset)
    if poll is not None:
        ns["poll"] = classmethod(poll)
    out = [type(parent_id, (Sidebar, bpy.types.Panel), ns)]
    for name, label, draw, shown in SECTIONS:
        ns = dict(bl_label=label, bl_space_type=space, bl_parent_id=parent_id, bl_options={"DEFAULT_CLOSED"},
                  draw=_draw_for(draw))
        if shown is not None:
            ns["poll"] = classmethod(_poll_for(shown))
        out.append(type(f"{parent_id}_{name}", (Sidebar, bpy.types.Panel), ns))
    return tuple(out)


class OMNINOISE_PT_neural_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Neural Noise Presets"
    preset_subdir = SUBDIRS["neural"]
    preset_operator = "script.execute_preset"
    preset_add_operator = "omninoise.neural_preset_add"


class OMNINOISE_OT_neural_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a neural noise preset (the swatches, their layout and the sampler)"""

    bl_idname = "omninoise.neural_preset_add"
    bl_label = "Add Neural Noise Preset"
    preset_menu = "OMNINOISE_PT_neural_presets"
    preset_subdir = SUBDIRS["neural"]
    preset_defines = ["p = bpy.context.scene.omninoise_neural"]
    preset_values = NEURAL_VALUES


def _draw_for(draw):
    def sub_draw(self, context):
        draw(_split(self.layout), context.scene.omninoise_neural)
    return sub_draw


def _poll_for(shown):
    def poll(cls, context):
        return shown(context.scene.omninoise_neural)
    return poll


def _shader_editor(cls, context):
    return getattr(context.space_data, "tree_type", "") == "ShaderNodeTree"


PANELS = _panels("IMAGE_EDITOR", "image") + _panels("NODE_EDITOR", "shader", _shader_editor)


classes = (OMNINOISE_PG_swatch, OMNINOISE_PG_neural, OMNINOISE_OT_neural_bake, OMNINOISE_OT_neural_bake_sequence,
           OMNINOISE_OT_neural_save_job, OMNINOISE_OT_neural_fit, OMNINOISE_OT_swatch_add,
           OMNINOISE_OT_swatch_thumbnails,
           OMNINOISE_OT_swatch_remove, OMNINOISE_OT_blend_map_new, OMNINOISE_UL_swatches, OMNINOISE_PT_neural_presets,
           OMNINOISE_OT_neural_preset_add) + PANELS


def attach():
    """What register() adds beyond the classes: the scene's neural noise settings."""
    bpy.types.Scene.omninoise_neural = PointerProperty(type=OMNINOISE_PG_neural)


def detach():
    del bpy.types.Scene.omninoise_neural
