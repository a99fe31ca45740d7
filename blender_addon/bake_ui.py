"""Bake Noise Volume / Bake Noise Image / Run Bake Job: panels and operators.

Settings live on the scene (``Scene.omninoise_bake``).  An operator builds a
Blender-free :class:`backend.bake.BakeSpec` on the main thread, runs it as a
:mod:`.tasks` worker (progress in the panel and the status bar, Esc or Cancel
stops it) and, when it ends, loads the files: a Volume object with a Principled
Volume material reading ``density`` / ``color`` / ``temperature``, or an image
in an Image Texture node.  With ``blender -b`` and the ``bpy`` module the same
operators run to completion before returning.
"""
from __future__ import annotations

import importlib
import json
import os

import bpy
from bl_operators.presets import AddPresetBase
from bl_ui.utils import PresetPanel
from bpy_extras.io_utils import ExportHelper
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, \
    IntVectorProperty, PointerProperty, StringProperty

from . import tasks
from .tasks import TaskOperator
from .. import backend
from ..backend.transfer import RANGE_LIMIT
from .bake_blender import (load_image, load_volume, output_folder, ramp_node,
                           set_ramp, transfer_from_color_ramp, world_bounds)
from .common import Sidebar
from .presets import SUBDIRS, transfer_preset_text
from .preferences import precision, threads
from .wave_nodes import settings_from_json, tree_settings_json
from .wave_ui import OMNINOISE_PG_wave, draw_wave_presets, draw_wave_settings, setting_label

__all__ = ["SaveJobOperator", "OMNINOISE_PG_bake", "build_spec", "transfer", "apply_transfer", "draw_progress",
           "classes", "attach", "detach"]

_OUTPUTS = [("real", "Value", "Real part"), ("imag", "Imaginary", "Imaginary part"),
            ("modulus", "Modulus", "Ridged: |noise|"), ("phase", "Phase", "Phasor: angle in radians")]
_CELLULAR = [("none", "None", "Plain wave noise"), ("polytope", "Polytope", "Distance to random polytope borders"),
             ("code", "Cell Code", "Random value per cell"), ("stit", "STIT", "Recursive STIT tessellation")]



def _with_precision(fn):
    """A worker function that runs ``fn(progress, cancel)`` with the preferences' neural precision, read
    now (on the main thread: preferences are not read from worker threads)."""
    prec = precision()

    def work(progress, cancel):
        importlib.import_module(f"{backend.__name__}.neural.precision").set_default_precision(prec)
        return fn(progress, cancel)
    return work

def apply_transfer(p, tf) -> None:
    """Set the bake panel's ramp, range, density and temperature to transfer function ``tf`` (the panel's
    temperature is one rise, from 0 K at its start to its maximum at the ramp's end)."""
    set_ramp(ramp_node().color_ramp, tf)
    p.range_min, p.range_max = tf.range
    p.density_scale = tf.density_scale
    p.use_temperature = tf.has_temperature
    if tf.has_temperature:
        p.temperature_start, p.temperature_max = tf.temperature[0][0], tf.temperature[-1][1]


def _is_wave_group(self, tree) -> bool:
    return bool(tree_settings_json(tree)) and tree.omninoise_wave.is_wave


class OMNINOISE_PG_bake(bpy.types.PropertyGroup):
    """Bake settings of a scene."""

    source: EnumProperty(name="Source", description="Where the wave noise settings come from", items=[
        ("SETTINGS", "Wave Noise", "Wave noise with the settings below"),
        ("NODE", "Wave Noise Node", "The settings of a Wave Noise node group in this file")], default="SETTINGS")
    wave: PointerProperty(type=OMNINOISE_PG_wave, name="Wave Noise", description="The wave noise the bake samples")
    node_group: PointerProperty(name="Node Group", type=bpy.types.NodeTree, poll=_is_wave_group,
                                description="A Wave Noise node group of this file whose settings the bake uses")
    output: EnumProperty(name="Output", items=_OUTPUTS, default="real",
                         description="Which value of the noise is baked")
    cellular: EnumProperty(name="Cellular", items=_CELLULAR, default="none",
                           description="Bake cells cut by the waves' planes instead of the noise itself")
    cell_size: FloatProperty(name="Cell Size", default=0.0, min=0.0, soft_max=10.0, subtype="DISTANCE",
                             description="Distance between the planes of one family, in scene units (0: from the "
                                         "frequency band, as the command line's default)")
    stit_probability: FloatProperty(name="Split Probability", default=0.5, min=0.0, max=1.0,
                                    description="STIT: how likely a cell is split again at each depth")
    stit_depth: IntProperty(name="Split Depth", default=3, min=0, max=8,
                            description="STIT: how many times cells may be split")
    # grid
    bounds_mode: EnumProperty(name="Bounds", description="The box in the scene that the bake fills", items=[
        ("OBJECT", "Active Object", "The active object's world bounding box"),
        ("CUSTOM", "Custom", "The box below")], default="OBJECT")
    bounds_min: FloatVectorProperty(name="Min", size=3, default=(-1.0, -1.0, -1.0), subtype="XYZ_LENGTH",
                                    description="The box's lowest corner, in scene units")
    bounds_max: FloatVectorProperty(name="Max", size=3, default=(1.0, 1.0, 1.0), subtype="XYZ_LENGTH",
                                    description="The box's highest corner, in scene units")
    volume_resolution: IntVectorProperty(name="Resolution", size=3, default=(128, 128, 128), min=1, max=4096,
                                         description="Voxels along X, Y and Z; memory grows with their product")
    image_resolution: IntVectorProperty(name="Resolution", size=2, default=(1024, 1024), min=1, max=16384,
                                        description="Image width and height in pixels")
    # time
    animated: BoolProperty(name="Animated", description="Bake a numbered sequence over a frame range "
                           "(needs wave speed, or 4D noise)", default=False)
    frame_start: IntProperty(name="Start", default=1, min=0, description="First frame of the baked sequence")
    frame_end: IntProperty(name="End", default=24, min=0, description="Last frame of the baked sequence")
    time: FloatProperty(name="Time", description="Time (4D: W) of the single bake, or of the first frame",
                        default=0.0)
    time_per_frame: FloatProperty(name="Time per Frame", default=1.0 / 24.0, min=0.0, soft_max=1.0, precision=4,
                                  description="How far the noise moves on from one frame to the next")
    # transfer function
    use_ramp: BoolProperty(name="Use Ramp", description="Map values through the ramp (off: raw values)",
                           default=True)
    range_min: FloatProperty(name="From", description="Noise value at the ramp's left end", default=-0.2,
                             min=-RANGE_LIMIT, max=RANGE_LIMIT)
    range_max: FloatProperty(name="To", description="Noise value at the ramp's right end", default=1.6,
                             min=-RANGE_LIMIT, max=RANGE_LIMIT)
    density_scale: FloatProperty(name="Density", description="Density = alpha x this", default=4.0, min=0.0,
                                 soft_max=50.0)
    use_temperature: BoolProperty(name="Temperature", description="Write a temperature grid (blackbody)",
                                  default=False)
    temperature_start: FloatProperty(name="Start", description="Ramp position where temperature rises from 0",
                                     default=0.2, min=0.0, max=1.0)
    temperature_max: FloatProperty(name="Max", description="Kelvin at the ramp's right end", default=1800.0,
                                   min=0.0, soft_max=6000.0)
    # output
    folder: StringProperty(name="Folder", subtype="DIR_PATH", default="//omninoise/",
                           description="Where baked files go ('//' = beside the .blend, or the cache "
                                       "folder while the file is unsaved)")
    name: StringProperty(name="Name", default="Noise",
                         description="Name of the baked files, and of the Volume object or image they load into")
    image_format: EnumProperty(name="Format", items=[("EXR", "OpenEXR", "Float image"),
                                                     ("PNG", "PNG", "8-bit preview")], default="EXR",
                               description="File type of the baked image")
    half: BoolProperty(name="Half Float", description="EXR: 16-bit half floats", default=False)
    # batch
    job_file: StringProperty(name="Job File", subtype="FILE_PATH", default="",
                             description="A TOML job file listing bakes (the same files as `omninoise bake`)")
    keep_going: BoolProperty(name="Keep Going", description="After a failed bake, carry on with the others")
    force: BoolProperty(name="Force", description="Re-bake outputs that are up to date")


# -- spec building (main thread) -------------------------------------------------------

def _settings(p: OMNINOISE_PG_bake):
    if p.source == "NODE":
        if p.node_group is None:
            raise backend.SettingError("node group", "pick a Wave Noise node group to bake")
        text = tree_settings_json(p.node_group)
        if text is None:
            raise backend.SettingError("node group", f"{p.node_group.name!r} holds no Wave Noise settings")
        s = settings_from_json(text)
    else:
        s = p.wave.to_settings(node=False)
    cells = {}
    if p.cellular != "none" and p.cell_size > 0.0:        # else the node's own, or the band's
        cells["cell_size"] = p.cell_size
    if p.cellular == "stit":
        cells.update(stit_probability=p.stit_probability, stit_depth=p.stit_depth)
    return s.replace(output=p.output, cellular=p.cellular, **cells)


def _bounds(p: OMNINOISE_PG_bake, context, rank: int) -> tuple:
    if p.bounds_mode == "OBJECT":
        obj = context.active_object
        if obj is None:
            raise backend.SettingError("bounds", "no active object: select one, or use Custom bounds")
        lo, hi = world_bounds(obj)
        flat = [a for a, l, h in zip("xyz"[:rank], lo, hi) if not h > l]
        if flat:        # a camera, light or empty; a plane for a volume
            raise backend.SettingError("bounds", f"the active object {obj.name!r} has no size along "
                                                 f"{', '.join(flat)}: select one that does, or use Custom bounds")
    else:
        lo, hi = tuple(p.bounds_min), tuple(p.bounds_max)
    if rank == 2:  # an image covers x, y at the box's middle height
        z = 0.5 * (lo[2] + hi[2])
        lo, hi = (lo[0], lo[1], z), (hi[0], hi[1], z)
    return lo, hi


def transfer(p: OMNINOISE_PG_bake):
    if not p.use_ramp:
        return None
    temp = ((p.temperature_start, 0.0), (1.0, p.temperature_max)) if p.use_temperature else ()
    return transfer_from_color_ramp(ramp_node().color_ramp, (p.range_min, p.range_max), p.density_scale, temp)


def build_spec(context, target: str):
    """BakeSpec for the scene's settings; target 'VOLUME' or 'IMAGE'."""
    p = context.scene.omninoise_bake
    rank = 3 if target == "VOLUME" else 2
    s = _settings(p)
    if rank == 3 and s.dim == 2:
        raise backend.SettingError("dimensions", "a volume needs 3D or 4D noise")
    res = tuple(p.volume_resolution) if rank == 3 else tuple(p.image_resolution)
    grid = backend.sources.BoxGrid(res, _bounds(p, context, rank))
    ext = ".vdb" if rank == 3 else (".exr" if p.image_format == "EXR" else ".png")
    name = bpy.path.clean_name(p.name or "Noise")
    folder = output_folder(p.folder)
    frames = (p.frame_start, p.frame_end) if p.animated else None
    path = os.path.join(folder, name + ("_####" if frames else "") + ext)
    return backend.bake.BakeSpec(name=name, source=backend.sources.WaveSource(s), grid=grid, output=path,
                                 transfer=transfer(p), frames=frames, time=p.time,
                                 time_step=p.time_per_frame, half=p.half).validate()


# -- operators -------------------------------------------------------------------------

def _message(text: str) -> None:
    wm = bpy.context.window_manager
    if wm is not None and hasattr(wm, "omninoise_message"):
        wm.omninoise_message = text
    print(f"OmniNoise: {text}")


#: the bake's own settings behind the backend's names (the wave settings' labels are read off their panel)
BAKE_LABELS = {"cell size": "Cell Size", "stit probability": "Split Probability", "stit depth": "Split Depth",
               "range": "From and To", "range[0]": "From", "range[1]": "To", "density_scale": "Density",
               "time": "Time", "time_step": "Time per Frame", "frames": "Start and End",
               "temperature[0][0]": "Temperature Start", "temperature[1][1]": "Temperature Max", "half": "Half Float"}


class _BakeOperator(TaskOperator):
    bl_options = {"REGISTER", "UNDO"}
    target = "VOLUME"

    def _label(self, setting: str) -> str:
        """The bake panel's label of a setting (Min Frequency, Time per Frame, From and To)."""
        return BAKE_LABELS.get(setting) or setting_label(bpy.context.scene.omninoise_bake.wave, setting)

    def _start(self, context, blocking: bool):
        spec = build_spec(context, self.target)
        target, obj = self.target, context.active_object
        raw = spec.transfer is None
        mat = None
        if target == "IMAGE" and obj is not None and obj.active_material is not None \
                and obj.active_material.node_tree is not None:
            mat = obj.active_material

        work = _with_precision(lambda progress, cancel: backend.bake.run_bake(spec, progress, cancel))

        def done(result):
            paths = [backend.bake.frame_path(spec.output, f) for f in spec.frame_list()]
            if target == "VOLUME":
                temp = spec.transfer is not None and spec.transfer.has_temperature
                load_volume(spec.name, paths, spec.frames, temp)
            else:
                load_image(spec.name, paths, spec.frames, raw, mat)
            _message(f"{spec.name}: {len(result.written)} written, {len(result.skipped)} up to date "
                     f"({spec.output})")

        def failed(msg):
            _message(f"{spec.name} failed: {msg}")

        task = tasks.Task(f"Baking {spec.name}", work, done, failed, threads=threads())
        return tasks.start(task, blocking=blocking)


class OMNINOISE_OT_bake_volume(_BakeOperator, bpy.types.Operator):
    """Bake noise through the ramp into an OpenVDB volume and add it as a Volume object"""

    bl_idname = "omninoise.bake_volume"
    bl_label = "Bake Noise Volume"
    target = "VOLUME"


class OMNINOISE_OT_bake_image(_BakeOperator, bpy.types.Operator):
    """Bake noise into an EXR or PNG image and add an Image Texture node"""

    bl_idname = "omninoise.bake_image"
    bl_label = "Bake Noise Image"
    target = "IMAGE"


class SaveJobOperator(ExportHelper):
    """A panel's bake saved as a TOML job file (:mod:`backend.job_file`), which `omninoise bake`, a farm or the
    Batch Job panel bakes again without Blender. A subclass names its panel's settings (``settings``: the scene's
    property group, with ``folder`` and ``name``), its bakes (``specs(context)``: BakeSpecs, SettingError naming
    what is wrong) and the files the panel reads (``reads(context)``), which a map beside the job may not
    replace."""

    bl_options = {"REGISTER"}      # writes files only: nothing in the .blend to undo

    filename_ext = ".toml"
    filter_glob: StringProperty(default="*.toml", options={"HIDDEN"})
    settings = ""

    def specs(self, context) -> list:
        raise NotImplementedError

    def reads(self, context) -> dict:
        """{path of a file the panel reads: who reads it} (none by default; :func:`backend.job_file.write_job`)."""
        return {}

    def invoke(self, context, event):
        """The file browser, at ``<bake name>.toml`` in the bake's output folder (the job then needs no output
        root, and the folder travels whole to another machine)."""
        p = getattr(context.scene, self.settings)
        if not self.filepath:
            try:
                folder = output_folder(p.folder)
            except backend.SettingError as exc:
                self.report({"ERROR"}, str(exc))
                return {"CANCELLED"}
            self.filepath = os.path.join(folder, bpy.path.clean_name(p.name or "Noise") + self.filename_ext)
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            if not self.filepath:
                raise backend.SettingError("file", "no file to save to: pick one in the file browser (a script: "
                                                   "filepath=...)")
            path = backend.job_file.check_job_file(bpy.path.abspath(self.filepath))     # its name first
            backend.job_file.write_job(path, self.specs(context), self.reads(context))
        except (backend.SettingError, OSError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        context.scene.omninoise_bake.job_file = path     # the Batch Job panel runs it next
        self.report({"INFO"}, f"Saved the job to {path}: omninoise bake {os.path.basename(path)}")
        return {"FINISHED"}


class OMNINOISE_OT_save_job(SaveJobOperator, bpy.types.Operator):
    """Save this bake, as the panel sets it, as a TOML job file that `omninoise bake`, a farm or the Batch Job panel
    bakes again without Blender"""

    bl_idname = "omninoise.save_job"
    bl_label = "Save as Job File"
    settings = "omninoise_bake"

    target: EnumProperty(name="Bake", default="VOLUME", description="Which of the panel's bakes the job holds",
                         items=[("VOLUME", "Volume", "The volume bake: an OpenVDB file or sequence"),
                                ("IMAGE", "Image", "The image bake: an EXR or PNG image or sequence")])

    @classmethod
    def description(cls, context, properties):
        return (f"Save the panel's {properties.target.lower()} bake as a TOML job file, for `omninoise bake`, a "
                "farm or the Batch Job panel to bake the same files without Blender")

    def specs(self, context) -> list:
        return [build_spec(context, self.target)]


class OMNINOISE_OT_cancel(bpy.types.Operator):
    """Stop the running OmniNoise bake (nothing half-written is kept)"""

    bl_idname = "omninoise.cancel"
    bl_label = "Cancel Bake"
    bl_options = {"REGISTER", "INTERNAL"}

    @classmethod
    def poll(cls, context):
        if tasks.current() is None:
            cls.poll_message_set("OmniNoise is not running a bake, preview or fit")
            return False
        return True

    def execute(self, context):
        tasks.cancel()
        return {"FINISHED"}


class OMNINOISE_OT_run_job(TaskOperator, bpy.types.Operator):
    """Run the bakes of a TOML job file (the same as `omninoise bake JOB.toml`)"""

    bl_idname = "omninoise.run_job"
    bl_label = "Run Bake Job"
    bl_options = {"REGISTER"}      # writes files only: nothing in the .blend to undo

    filepath: StringProperty(name="Job File", subtype="FILE_PATH", default="",
                             description="The TOML job file to run (empty: the panel's Job File)")
    keep_going: BoolProperty(name="Keep Going", default=False,
                             description="After a failed bake, carry on with the others")
    force: BoolProperty(name="Force", default=False, description="Re-bake outputs that are up to date")
    filter_glob: StringProperty(default="*.toml", options={"HIDDEN"})

    def invoke(self, context, event):
        """From a menu with no job file chosen: the file browser first, then the job in the background."""
        if not (self.filepath or context.scene.omninoise_bake.job_file) and not bpy.app.background:
            self._browsed = True
            context.window_manager.fileselect_add(self)
            return {"RUNNING_MODAL"}
        return super().invoke(context, event)

    def execute(self, context):
        if getattr(self, "_browsed", False):      # the file browser's confirm: run it as invoke would
            self._browsed = False
            context.scene.omninoise_bake.job_file = self.filepath
            self._task = self._begin(context, blocking=False)
            if self._task is None:
                return {"CANCELLED"}
            context.window_manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}
        return super().execute(context)

    def _start(self, context, blocking):
        p = context.scene.omninoise_bake
        path = bpy.path.abspath(self.filepath or p.job_file)
        if not path:
            self.report({"ERROR"}, "job file: pick a TOML job file to run")
            return None
        if not os.path.isfile(path):
            self.report({"ERROR"}, f"job file: no file at {path}")
            return None
        keep_going, force = self.keep_going or p.keep_going, self.force or p.force

        work = _with_precision(lambda progress, cancel: backend.jobs.run_job(
            path, keep_going=keep_going, force=force, progress=progress, cancel=cancel))

        def done(outcomes):
            bad = [o for o in outcomes if o.status in ("invalid", "failed", "cancelled")]
            text = "; ".join(f"{o.name}: {o.status}" for o in outcomes)
            _message(text if not bad else "; ".join(o.message for o in bad))
            if bad:
                raise RuntimeError(bad[0].message)

        return tasks.start(tasks.Task(f"Job {os.path.basename(path)}", work, done, _message, threads()),
                           blocking=blocking)


# -- panels ----------------------------------------------------------------------------

def draw_progress(layout) -> bool:
    """Progress bar and Cancel button while a task runs; True if one is running."""
    task = tasks.current()
    if task is None:
        msg = bpy.context.window_manager.omninoise_message
        if msg:
            layout.label(text=msg, icon="INFO")
        return False
    row = layout.row(align=True)
    row.progress(factor=task.progress, type="BAR", text=f"{task.label}  {task.progress * 100:.0f}%")
    row.operator(OMNINOISE_OT_cancel.bl_idname, text="", icon="CANCEL")
    return True


class _Panel(Sidebar):
    bl_space_type = "VIEW_3D"


class OMNINOISE_PT_bake(_Panel, bpy.types.Panel):
    bl_label = "Bake Noise"

    def draw_header_preset(self, context):
        p = context.scene.omninoise_bake
        if p.source == "SETTINGS":
            draw_wave_presets(self.layout, p.wave)

    def draw(self, context):
        p = context.scene.omninoise_bake
        layout = self.layout
        layout.use_property_split = True
        draw_progress(layout)
        layout.prop(p, "source")
        if p.source == "NODE":
            layout.prop(p, "node_group")
        else:
            draw_wave_settings(layout, p.wave)
        layout.prop(p, "output")
        layout.prop(p, "cellular")
        if p.cellular != "none":
            layout.prop(p, "cell_size")
        if p.cellular == "stit":
            layout.prop(p, "stit_probability")
            layout.prop(p, "stit_depth")


class OMNINOISE_PT_bake_ramp(_Panel, bpy.types.Panel):
    bl_label = "Transfer Function"
    bl_parent_id = "OMNINOISE_PT_bake"

    def draw_header(self, context):
        self.layout.prop(context.scene.omninoise_bake, "use_ramp", text="")

    def draw_header_preset(self, context):
        OMNINOISE_PT_transfer_presets.draw_panel_header(self.layout)

    def draw(self, context):
        p = context.scene.omninoise_bake
        layout = self.layout
        layout.active = p.use_ramp
        node = ramp_node(create=False)
        if node is None:
            layout.operator(OMNINOISE_OT_init_ramp.bl_idname, icon="COLOR")
        else:
            layout.template_color_ramp(node, "color_ramp", expand=True)
        layout.use_property_split = True
        col = layout.column(align=True)
        col.prop(p, "range_min")
        col.prop(p, "range_max")
        layout.prop(p, "density_scale")
        layout.prop(p, "use_temperature")
        if p.use_temperature:
            col = layout.column(align=True)
            col.prop(p, "temperature_start")
            col.prop(p, "temperature_max")


class OMNINOISE_OT_init_ramp(bpy.types.Operator):
    """Create the ramp the bake panel edits (the clouds preset, to start from)"""

    bl_idname = "omninoise.init_ramp"
    bl_label = "Create Ramp"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    def execute(self, context):
        apply_transfer(context.scene.omninoise_bake, backend.transfer.preset("clouds"))
        return {"FINISHED"}


class OMNINOISE_PT_bake_output(_Panel, bpy.types.Panel):
    bl_label = "Grid and Output"
    bl_parent_id = "OMNINOISE_PT_bake"

    def draw(self, context):
        p = context.scene.omninoise_bake
        layout = self.layout
        layout.use_property_split = True
        layout.prop(p, "bounds_mode")
        if p.bounds_mode == "CUSTOM":
            layout.prop(p, "bounds_min")
            layout.prop(p, "bounds_max")
        layout.prop(p, "animated")
        if p.animated:
            col = layout.column(align=True)
            col.prop(p, "frame_start")
            col.prop(p, "frame_end")
            layout.prop(p, "time_per_frame")
        layout.prop(p, "time")
        layout.prop(p, "folder")
        layout.prop(p, "name")
        busy = tasks.current() is not None
        box = layout.box()
        box.prop(p, "volume_resolution")
        row = box.row(align=True)
        row.enabled = not busy
        row.operator(OMNINOISE_OT_bake_volume.bl_idname, icon="VOLUME_DATA")
        row.operator(OMNINOISE_OT_save_job.bl_idname, text="", icon="EXPORT").target = "VOLUME"
        box = layout.box()
        box.prop(p, "image_resolution")
        box.prop(p, "image_format")
        if p.image_format == "EXR":
            box.prop(p, "half")
        row = box.row(align=True)
        row.enabled = not busy
        row.operator(OMNINOISE_OT_bake_image.bl_idname, icon="IMAGE_DATA")
        row.operator(OMNINOISE_OT_save_job.bl_idname, text="", icon="EXPORT").target = "IMAGE"


class OMNINOISE_PT_bake_job(_Panel, bpy.types.Panel):
    bl_label = "Batch Job"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        p = context.scene.omninoise_bake
        layout = self.layout
        layout.prop(p, "job_file")
        row = layout.row()
        row.prop(p, "keep_going")
        row.prop(p, "force")
        row = layout.row()
        row.enabled = tasks.current() is None and bool(p.job_file)
        op = row.operator(OMNINOISE_OT_run_job.bl_idname, icon="PLAY")
        op.filepath = p.job_file


# -- transfer function presets (Blender's preset menu in the Transfer Function panel's header) ------------

class OMNINOISE_OT_set_transfer(bpy.types.Operator):
    """Set the bake panel's ramp, range, density and temperature from a transfer function (a preset's JSON)"""

    bl_idname = "omninoise.set_transfer"
    bl_label = "Set Transfer Function"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    transfer: StringProperty(name="Transfer Function", description="The ramp as JSON: range, interpolation, "
                             "density_scale, stops and temperature (as in a job file)", options={"SKIP_SAVE"})

    def execute(self, context):
        if not self.transfer.strip():
            self.report({"ERROR"}, "transfer function preset: none given (a preset passes its ramp as JSON)")
            return {"CANCELLED"}
        try:
            tf = backend.transfer.transfer_from_dict(json.loads(self.transfer), "preset")
        except (ValueError, backend.SettingError) as exc:
            self.report({"ERROR"}, f"transfer function preset: {exc}")
            return {"CANCELLED"}
        apply_transfer(context.scene.omninoise_bake, tf)
        return {"FINISHED"}


class OMNINOISE_PT_transfer_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Transfer Function Presets"
    preset_subdir = SUBDIRS["transfer"]
    preset_operator = "script.execute_preset"
    preset_add_operator = "omninoise.transfer_preset_add"


class OMNINOISE_OT_transfer_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a transfer function preset (the ramp, its range, density and temperature)"""

    bl_idname = "omninoise.transfer_preset_add"
    bl_label = "Add Transfer Function Preset"
    preset_menu = "OMNINOISE_PT_transfer_presets"
    preset_subdir = SUBDIRS["transfer"]

    def add(self, context, filepath):
        p = context.scene.omninoise_bake
        use = p.use_ramp
        p.use_ramp = True
        try:
            text = transfer_preset_text(transfer(p))
        finally:
            p.use_ramp = use
        with open(filepath, "w", encoding="utf-8") as fh:
            fh.write(text)


def _statusbar(self, context):
    task = tasks.current()
    if task is None:
        return
    row = self.layout.row(align=True)
    row.progress(factor=task.progress, type="BAR", text=f"OmniNoise: {task.label} {task.progress * 100:.0f}%")
    row.operator(OMNINOISE_OT_cancel.bl_idname, text="", icon="CANCEL")


classes = (OMNINOISE_PG_bake, OMNINOISE_OT_bake_volume, OMNINOISE_OT_bake_image, OMNINOISE_OT_save_job,
           OMNINOISE_OT_cancel, OMNINOISE_OT_run_job, OMNINOISE_OT_init_ramp, OMNINOISE_PT_bake, OMNINOISE_PT_bake_ramp,
           OMNINOISE_PT_bake_output, OMNINOISE_PT_bake_job, OMNINOISE_OT_set_transfer, OMNINOISE_PT_transfer_presets,
           OMNINOISE_OT_transfer_preset_add)


def attach():
    """What register() adds beyond the classes: the scene's bake settings, the message line, the status bar."""
    bpy.types.Scene.omninoise_bake = PointerProperty(type=OMNINOISE_PG_bake)
    bpy.types.WindowManager.omninoise_message = StringProperty(options={"SKIP_SAVE"})
    bpy.types.STATUSBAR_HT_header.append(_statusbar)


def detach():
    tasks.cancel()
    bpy.types.STATUSBAR_HT_header.remove(_statusbar)
    del bpy.types.WindowManager.omninoise_message
    del bpy.types.Scene.omninoise_bake


