"""Wave Noise in the node editors: Add-menu entry, settings panel, live rebuild.

The node an artist adds is a plain group node whose tree :mod:`.wave_nodes`
builds; its settings live on the tree (``NodeTree.omninoise_wave``).  Editing a
setting rebuilds the inner nodes in place: the interface never changes, so
links to the node survive.  A .blend keeps rendering without the extension,
because the group is made of Blender's own nodes and its tables are packed (or,
in its OSL form, of one Script node whose text and bytecode are in the file).

The form follows the scene by default (Implementation: Automatic): the OSL script
where Cycles runs Open Shading Language, several times faster there; Blender's
nodes everywhere else (EEVEE, Cycles' SVM on any device, Geometry Nodes).  Groups
switch before each render, on file load, after depsgraph updates and when the
engine or the OSL switch changes in the interface.
"""
from __future__ import annotations

import time

import bpy
from bl_operators.presets import AddPresetBase
from bl_ui.utils import PresetPanel
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, \
    PointerProperty, StringProperty

from .. import backend
from .common import Sidebar
from .presets import LOADING, SUBDIRS, WAVE_VALUES, loading
from .wave_nodes import add_wave_node, build_wave_group, new_wave_tree, tree_implementation

_SPECTRA = [("gaussian", "Gaussian", "Feature sizes spread smoothly around the middle of the band"),
            ("bandpass", "Band-Pass", "Every frequency of the band equally strong: even, busy detail"),
            ("fractal", "Fractal", "Large features strongest, detail fading by the exponent (clouds, terrain)"),
            ("white", "White", "Every frequency up to the top of the band: grainy"),
            ("blue", "Blue", "High frequencies strongest: fine, even grain"),
            ("brown", "Brown", "Low frequencies much the strongest: soft, rolling"),
            ("twolevel", "Two-Level", "Two separate bands: coarse shapes with fine detail")]
_WAVEFORMS = [("gaussian", "Gaussian", "Random-phase waves (Gaussian noise)"),
              ("crystal", "Crystal", "Stepped waveform: faceted, crystal-like"),
              ("wired", "Wired", "Impulse waveform: thin wires")]
_ANISO = [("none", "Isotropic", "Directions over the whole (half) sphere"),
          ("lobes", "Lobe", "Directions within a cone around an axis: streaks along it"),
          ("axes", "Per Axis", "Its own frequency band along each axis: stretched features")]
_IMPLEMENTATIONS = [
    ("AUTO", "Automatic", "The OSL script where the scene renders with Cycles and Open Shading Language, "
     "Blender's nodes everywhere else"),
    ("NODES", "Nodes", "Blender's math nodes: Cycles on any device, EEVEE and Geometry Nodes"),
    ("OSL", "OSL Script", "One compiled OSL script: several times faster, but only Cycles with Open Shading "
     "Language renders it (elsewhere it is black)")]
#: most directions Cycles' shader stack holds, per dimension (tests/blender/test_wave_node.py); OSL has no such limit
MAX_DIRECTIONS = {2: 64, 3: 32, 4: 32}


def scene_runs_osl(scene) -> bool:
    """True when ``scene`` renders with Cycles and its Open Shading Language switch is on."""
    return (scene is not None and scene.render.engine == "CYCLES"
            and bool(getattr(getattr(scene, "cycles", None), "shading_system", False)))


def scene_form(scene) -> str:
    """'osl' where ``scene`` renders with Cycles and Open Shading Language and this Blender compiles OSL, else
    'nodes': the Automatic form of a Wave Noise shader tree."""
    from .wave_osl import osl_available

    return "osl" if scene_runs_osl(scene) and osl_available() else "nodes"


def wanted_implementation(props, tree, scene) -> str:
    """'nodes' or 'osl': the form a Wave Noise tree should be built in for ``scene``."""
    if tree.bl_idname != "ShaderNodeTree" or props.implementation == "NODES":
        return "nodes"
    if props.implementation == "OSL":
        return "osl"
    return scene_form(scene)


def rebuild_tree(props, scene) -> None:
    """Rebuild the tree holding ``props`` from them; errors go to ``props.error`` (shown in the panel)."""
    tree = props.id_data
    try:
        if props.is_cellular:
            from .cellular_nodes import build_cellular_group

            build_cellular_group(props.to_settings(), tree=tree)
        else:
            form = wanted_implementation(props, tree, scene)
            build_wave_group(props.to_settings(node=form == "nodes"), tree=tree, implementation=form)
        props.error = ""
    except backend.SettingError as e:
        props.error = f"{setting_label(props, e.setting)}: {e.message}"


#: wave settings whose panel property has another name
_PROPERTIES = {"dim": "dimensions", "lobes": "axis", "axis_spectra": "axis_scale"}


def setting_label(props, setting: str) -> str:
    """The panel's label of the property of ``props`` (an :class:`OMNINOISE_PG_wave`) behind a wave setting's dotted
    name ("spectrum.fmax" -> "Max Frequency", "axis_spectra[0].fmin" -> "Axis Frequency"), or the name itself."""
    ident = backend.wavenoise.settings.field_of(setting)
    prop = props.bl_rna.properties.get(_PROPERTIES.get(ident, ident))
    return prop.name if prop is not None else setting


def _rebuild(self, context) -> None:
    if loading(self):       # a preset is setting the values one by one: it rebuilds once, after the last
        return
    rebuild(self, context)


#: seconds a setting must rest before its group is rebuilt in the interface: a slider being dragged sends a change
#: per step, and a rebuild of every node takes 0.04 s (3D, 16 directions) to 0.6 s (4D, 64 directions) of the
#: interface's thread
REBUILD_DELAY_S = 0.25
_due: dict = {}             # the trees whose settings changed: node group name -> the scene's name, or None
_due_at = [0.0]             # when the last of those changes rests long enough (time.monotonic())


def deferred() -> bool:
    """Whether a setting's change rebuilds its group once the setting rests (the interface), not at once
    (background Blender and scripts, which read the group right after setting it)."""
    return not bpy.app.background


def rebuild(props, context) -> None:
    """Rebuild the node group holding ``props`` (nothing for the bake panel's settings, which no tree holds): at
    once in scripts, in the interface once its settings rest for REBUILD_DELAY_S (:func:`rebuild_due`)."""
    if not props.is_wave or getattr(props.id_data, "is_evaluated", False):
        return
    scene = getattr(context, "scene", None)
    if not deferred():
        rebuild_tree(props, scene)
        return
    _due[props.id_data.name] = None if scene is None else scene.name
    _due_at[0] = time.monotonic() + REBUILD_DELAY_S
    if not bpy.app.timers.is_registered(rebuild_due):
        bpy.app.timers.register(rebuild_due, first_interval=REBUILD_DELAY_S)


def rebuild_due():
    """The timer behind :func:`rebuild`: each group whose settings changed, rebuilt once they rest (a group or
    scene removed meanwhile is skipped); seconds until it looks again, or None when nothing is due."""
    wait = _due_at[0] - time.monotonic()
    if wait > 0.0:
        return wait
    due = dict(_due)
    _due.clear()
    for name, scene_name in due.items():
        tree = bpy.data.node_groups.get(name)
        if tree is not None:
            rebuild_tree(tree.omninoise_wave, None if scene_name is None else bpy.data.scenes.get(scene_name))
    wm = getattr(bpy.context, "window_manager", None)
    for window in wm.windows if wm is not None else ():     # the node editors' panels show a setting's error
        for area in window.screen.areas:
            if area.type == "NODE_EDITOR":
                area.tag_redraw()
    return None


_last_scene_state = [None]


@persistent
def follow_render_settings(*_args) -> None:
    """Automatic Wave Noise groups follow the scene: OSL form when Cycles runs OSL, nodes otherwise; so do the
    Wave Noise trees inside procedural solids' groups (procedural_nodes.follow_form).

    Runs before renders, after depsgraph updates and file loads, and when the render engine or
    Cycles' Open Shading Language switch is changed in the interface (message bus); it only
    compares those two settings and the number of node groups unless one of them changed."""
    scene = getattr(bpy.context, "scene", None)
    # the node groups' count too: a group appended (an asset's material) or built is brought to the scene's form
    state = (scene.name, scene_runs_osl(scene), len(bpy.data.node_groups)) if scene is not None else None
    if state == _last_scene_state[0]:
        return
    _last_scene_state[0] = state
    for tree in bpy.data.node_groups:
        props = getattr(tree, "omninoise_wave", None)
        if (props is None or not props.is_wave or props.is_cellular or props.implementation != "AUTO"
                or tree.library is not None):
            continue
        if tree_implementation(tree) != wanted_implementation(props, tree, scene):
            rebuild_tree(props, scene)
    from .procedural_nodes import follow_form

    follow_form(scene_form(scene))


class OMNINOISE_PG_wave(bpy.types.PropertyGroup):
    """Settings of a Wave Noise group (stored with its node tree)."""

    is_wave: BoolProperty(default=False, options={"HIDDEN"})
    is_cellular: BoolProperty(default=False, options={"HIDDEN"})
    cell_size: FloatProperty(name="Cell Size", description="Distance between the planes of one family (cellular)",
                             default=0.5, min=0.001, soft_max=10.0, update=_rebuild)
    error: StringProperty(default="", options={"HIDDEN"})
    dimensions: EnumProperty(name="Dimensions", items=[("2", "2D", "Noise over a plane (X, Y)"),
                                                       ("3", "3D", "Noise through space (X, Y, Z)"),
                                                       ("4", "4D", "Space plus W: animate W for noise that changes "
                                                                   "in place")],
                             default="3", update=_rebuild, description="How many coordinates the noise varies over")
    directions: IntProperty(name="Directions", description="Number of wave directions (cost grows linearly)",
                            default=16, min=1, soft_max=64, max=256, update=_rebuild)
    spectrum: EnumProperty(name="Spectrum", items=_SPECTRA, default="gaussian", update=_rebuild,
                           description="How strong each feature size is within the frequency band")
    fmin: FloatProperty(name="Min Frequency", description="Lower band limit, cycles per unit (after Scale)",
                        default=2.0, min=0.0, soft_max=64.0, update=_rebuild)
    fmax: FloatProperty(name="Max Frequency", description="Upper band limit, cycles per unit (after Scale)",
                        default=8.0, min=0.01, soft_max=64.0, update=_rebuild)
    exponent: FloatProperty(name="Exponent", description="Fractal spectrum falls as 1/f^exponent",
                            default=1.0, min=0.0, max=4.0, update=_rebuild)
    waveform: EnumProperty(name="Waveform", items=_WAVEFORMS, default="gaussian", update=_rebuild,
                           description="The profile of each wave, which sets the noise's character")
    anisotropy: EnumProperty(name="Anisotropy", items=_ANISO, default="none", update=_rebuild,
                             description="Whether the noise has a direction")
    axis: FloatVectorProperty(name="Axis", size=3, default=(1.0, 0.0, 0.0), update=_rebuild,
                              description="The direction the lobe's waves run along")
    spread: FloatProperty(name="Spread", description="Half-angle of the lobe, degrees", default=20.0,
                          min=1.0, max=90.0, update=_rebuild)
    axis_scale: FloatVectorProperty(name="Axis Frequency", description="Band limits scaled per axis",
                                    size=3, default=(1.0, 2.0, 0.5), min=0.05, soft_max=8.0, update=_rebuild)
    seed: IntProperty(name="Seed", default=0, min=0, max=(1 << 24) - 1, update=_rebuild,
                      description="Another seed gives another noise of the same look")
    speed: FloatProperty(name="Speed", description="How fast the waves travel as the Time input grows, units per "
                         "unit of time; 0 keeps the noise still", default=0.0, soft_min=-10.0, soft_max=10.0,
                         update=_rebuild)
    implementation: EnumProperty(name="Implementation", items=_IMPLEMENTATIONS, default="AUTO", update=_rebuild,
                                 description="How the node computes the noise: from Blender's nodes or as one OSL "
                                             "script")

    def to_settings(self, node: bool = True):
        """WaveSettings; ``node`` checks the live node's limits (bakes take any number of directions)."""
        dim = int(self.dimensions)
        if node and self.directions > MAX_DIRECTIONS[dim]:
            raise backend.SettingError("directions", f"at most {MAX_DIRECTIONS[dim]} in {dim}D (Cycles' shader "
                                       "stack); use Cycles with Open Shading Language or a bake for more")
        sp = backend.Spectrum(self.spectrum, self.fmin, self.fmax, self.exponent)
        kw = {}
        if self.anisotropy == "lobes":
            axis = (tuple(self.axis) + (0.0,))[:dim]
            kw = dict(anisotropy="lobes", lobes=((axis, 1.0),), spread=self.spread)
        elif self.anisotropy == "axes":
            scales = list(self.axis_scale) + [1.0]
            kw = dict(anisotropy="axes", axis_spectra=tuple(
                backend.Spectrum(self.spectrum, self.fmin * scales[a], self.fmax * scales[a], self.exponent)
                for a in range(dim)))
        if self.is_cellular:
            kw.update(cellular="polytope", cell_size=self.cell_size)
        return backend.WaveSettings(dim=dim, spectrum=sp, directions=self.directions, seed=self.seed,
                                    speed=self.speed, waveform=self.waveform, **kw)


def _wave_tree(context):
    node = getattr(context, "active_node", None)
    tree = getattr(node, "node_tree", None) if node is not None else None
    if tree is not None and tree.omninoise_wave.is_wave:
        return tree
    return None


class _AddGroupNode:
    """Add-menu operator: a new group tree (``make_tree``) as a selected, active node at the cursor."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        space = context.space_data
        if (space is not None and space.type == "NODE_EDITOR" and space.edit_tree is not None
                and space.tree_type in ("ShaderNodeTree", "GeometryNodeTree")):
            return True
        cls.poll_message_set("Adds a node to a shader or geometry node tree: open one in a node editor")
        return False

    def execute(self, context):
        space = context.space_data
        edit = space.edit_tree
        try:
            tree = self.make_tree(self.bl_label, space.tree_type)
        except backend.SettingError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for n in edit.nodes:
            n.select = False
        node = add_wave_node(edit, tree, tuple(space.cursor_location))
        node.select = True
        edit.nodes.active = node
        return {"FINISHED"}


class OMNINOISE_OT_add_wave_noise(_AddGroupNode, bpy.types.Operator):
    """Add a Wave Noise node: a sum of randomly oriented waves, editable like Blender's own textures"""

    bl_idname = "node.omninoise_add_wave_noise"
    bl_label = "Wave Noise"

    @staticmethod
    def make_tree(name, tree_type):
        return new_wave_node_tree(name, tree_type)


class OMNINOISE_OT_add_wave_cellular(_AddGroupNode, bpy.types.Operator):
    """Add a Wave Cellular node: cells cut by random planes (cracked, faceted and tiled looks)"""

    bl_idname = "node.omninoise_add_wave_cellular"
    bl_label = "Wave Cellular"

    @staticmethod
    def make_tree(name, tree_type):
        return new_cellular_node_tree(name, tree_type)


def new_cellular_node_tree(name: str, tree_type: str) -> bpy.types.NodeTree:
    """A Wave Cellular group (outputs Cell and Distance) from the default panel settings."""
    from .cellular_nodes import build_cellular_group, new_cellular_tree

    tree = new_cellular_tree(name, tree_type)
    props = tree.omninoise_wave
    props.is_cellular = True
    props.directions = 4
    build_cellular_group(props.to_settings(), tree=tree)
    props.is_wave = True
    return tree


def new_wave_node_tree(name: str, tree_type: str, scene=None) -> bpy.types.NodeTree:
    """A Wave Noise group built from the default panel settings, its settings stored on it; in the
    form ``scene`` (default: the context's) renders fastest (:func:`wanted_implementation`).

    Raises backend.SettingError (and leaves no tree behind) when the settings are invalid.
    """
    tree = new_wave_tree(name, tree_type)
    props = tree.omninoise_wave
    try:
        form = wanted_implementation(props, tree, scene if scene is not None else getattr(bpy.context, "scene", None))
        build_wave_group(props.to_settings(node=form == "nodes"), tree=tree, implementation=form)
    except backend.SettingError:
        bpy.data.node_groups.remove(tree)
        raise
    props.is_wave = True
    return tree


class OMNINOISE_PT_wave_node(Sidebar, bpy.types.Panel):
    bl_label = "Wave Noise"
    bl_space_type = "NODE_EDITOR"

    @classmethod
    def poll(cls, context):
        return _wave_tree(context) is not None

    def draw_header_preset(self, context):
        draw_wave_presets(self.layout, _wave_tree(context).omninoise_wave)

    def draw(self, context):
        self.layout.use_property_split = True
        draw_wave_settings(self.layout, _wave_tree(context).omninoise_wave)


def draw_wave_presets(layout, props) -> None:
    """The wave preset menu (+ and −) for the settings ``props`` (a node tree's, or the bake panel's)."""
    layout.context_pointer_set("omninoise_wave", props)
    OMNINOISE_PT_wave_presets.draw_panel_header(layout)


def draw_wave_settings(layout, props) -> None:
    """The settings of an :class:`OMNINOISE_PG_wave`, mirroring Blender's texture nodes."""
    layout.prop(props, "dimensions")
    layout.prop(props, "directions")
    col = layout.column(heading="Spectrum")
    col.prop(props, "spectrum", text="Spectrum")
    col.prop(props, "fmin")
    col.prop(props, "fmax")
    if props.spectrum == "fractal":
        col.prop(props, "exponent")
    layout.prop(props, "waveform")
    layout.prop(props, "anisotropy")
    if props.anisotropy == "lobes":
        layout.prop(props, "axis")
        layout.prop(props, "spread")
    elif props.anisotropy == "axes":
        layout.prop(props, "axis_scale")
    layout.prop(props, "seed")
    if props.is_cellular:
        layout.prop(props, "cell_size")
    else:
        layout.prop(props, "speed")
        if props.id_data.bl_idname == "ShaderNodeTree":
            layout.prop(props, "implementation")
            form = tree_implementation(props.id_data)
            layout.label(text="In use: OSL script" if form == "osl" else "In use: Blender's nodes", icon="INFO")
            if form != "osl" and props.implementation == "AUTO":
                layout.label(text="Cycles with Open Shading Language runs it faster")
    if props.error:
        layout.label(text=props.error, icon="ERROR")


def _menu(self, context):
    self.layout.operator(OMNINOISE_OT_add_wave_noise.bl_idname, text="Wave Noise (OmniNoise)")
    self.layout.operator(OMNINOISE_OT_add_wave_cellular.bl_idname, text="Wave Cellular (OmniNoise)")


def _HANDLERS():
    h = bpy.app.handlers
    return (h.render_pre, h.depsgraph_update_post, h.load_post)


_MSGBUS_OWNER = object()


@persistent
def _subscribe(*_args) -> None:
    """Message-bus subscriptions (cleared by every file load) to the settings the Automatic form follows.
    Interface edits of Cycles' Python-defined settings do not always reach the depsgraph handlers."""
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    keys = [(bpy.types.RenderSettings, "engine")]
    cycles = getattr(bpy.types, "CyclesRenderSettings", None)
    if cycles is not None:
        keys.append((cycles, "shading_system"))
    for key in keys:
        bpy.msgbus.subscribe_rna(key=key, owner=_MSGBUS_OWNER, args=(), notify=follow_render_settings)


# -- wave noise presets (Blender's preset menu in the Wave Noise and Bake Noise panels' headers) ----------

def _wave_reset(context, filepath) -> None:
    props = getattr(context, "omninoise_wave", None)
    if props is not None:
        LOADING.add(props.as_pointer())


def _wave_post(context, filepath) -> None:
    props = getattr(context, "omninoise_wave", None)
    if props is not None:
        LOADING.discard(props.as_pointer())
        rebuild(props, context)


class OMNINOISE_PT_wave_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Wave Noise Presets"
    preset_subdir = SUBDIRS["wave"]
    preset_operator = "script.execute_preset"
    preset_add_operator = "omninoise.wave_preset_add"
    reset_cb = staticmethod(_wave_reset)
    post_cb = staticmethod(_wave_post)


class OMNINOISE_OT_wave_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a wave noise preset (spectrum, waveform, directions, anisotropy and speed)"""

    bl_idname = "omninoise.wave_preset_add"
    bl_label = "Add Wave Noise Preset"
    preset_menu = "OMNINOISE_PT_wave_presets"
    preset_subdir = SUBDIRS["wave"]
    preset_defines = ["props = bpy.context.omninoise_wave"]
    preset_values = WAVE_VALUES


MENUS = ("NODE_MT_category_shader_texture", "NODE_MT_category_GEO_TEXTURE")
classes = (OMNINOISE_PG_wave, OMNINOISE_OT_add_wave_noise, OMNINOISE_OT_add_wave_cellular, OMNINOISE_PT_wave_node,
           OMNINOISE_PT_wave_presets, OMNINOISE_OT_wave_preset_add)


def attach():
    """What register() adds beyond the classes: the node tree's settings, the render-settings handlers, the
    Add-menu entries."""
    bpy.types.NodeTree.omninoise_wave = PointerProperty(type=OMNINOISE_PG_wave)
    for handlers in _HANDLERS():
        if follow_render_settings not in handlers:
            handlers.append(follow_render_settings)
    if _subscribe not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_subscribe)
    _subscribe()
    for m in MENUS:
        menu = getattr(bpy.types, m, None)
        if menu is not None:
            menu.append(_menu)


def detach():
    if bpy.app.timers.is_registered(rebuild_due):
        bpy.app.timers.unregister(rebuild_due)
    _due.clear()
    for handlers in _HANDLERS():
        if follow_render_settings in handlers:
            handlers.remove(follow_render_settings)
    if _subscribe in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_subscribe)
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    _last_scene_state[0] = None
    for m in MENUS:
        menu = getattr(bpy.types, m, None)
        if menu is not None:
            menu.remove(_menu)
    del bpy.types.NodeTree.omninoise_wave
