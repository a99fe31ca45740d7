"""The extension's operators in the menus where Blender puts such things, so F3 finds each by its name.

Image Editor > Image > OmniNoise      image bakes (wave noise, neural noise and its sequence, fit, tileable image)
3D Viewport > Add > OmniNoise         a baked noise volume
3D Viewport > Object > OmniNoise      bakes onto the active object (solid texture, noise volume and image)
Shader and Geometry Node Editors > Add > Texture: Wave Noise, Wave Cellular (:mod:`.wave_ui`)
Render > Run Bake Job, Save Noise / Neural Bake as Job    a TOML job file: run one, or save the Bake Noise or
                                                          Neural Noise panel's bake
"""
from __future__ import annotations

import bpy

__all__ = ["MENUS", "APPENDED", "classes", "attach", "detach"]


class OMNINOISE_MT_image(bpy.types.Menu):
    """OmniNoise's image bakes"""

    bl_idname = "OMNINOISE_MT_image"
    bl_label = "OmniNoise"

    def draw(self, context):
        layout = self.layout
        layout.operator_context = "INVOKE_DEFAULT"
        layout.operator("omninoise.bake_image", icon="IMAGE_DATA")
        layout.separator()
        layout.operator("omninoise.neural_bake", icon="RENDER_STILL")
        layout.operator("omninoise.neural_bake_sequence", icon="RENDER_ANIMATION")
        layout.operator("omninoise.neural_fit", icon="EYEDROPPER")
        layout.separator()
        layout.operator("omninoise.solid_tileable", icon="IMAGE_DATA")


class OMNINOISE_MT_add(bpy.types.Menu):
    """OmniNoise's objects to add"""

    bl_idname = "OMNINOISE_MT_add"
    bl_label = "OmniNoise"

    def draw(self, context):
        layout = self.layout
        layout.operator_context = "INVOKE_DEFAULT"
        layout.operator("omninoise.bake_volume", text="Noise Volume", icon="VOLUME_DATA")


class OMNINOISE_MT_object(bpy.types.Menu):
    """OmniNoise's bakes onto the active object"""

    bl_idname = "OMNINOISE_MT_object"
    bl_label = "OmniNoise"

    def draw(self, context):
        layout = self.layout
        layout.operator_context = "INVOKE_DEFAULT"
        layout.operator("omninoise.solid_bake", icon="RENDER_STILL")
        layout.operator("omninoise.solid_preview", icon="HIDE_OFF")
        layout.operator("omninoise.solid_tile_material", icon="MOD_UVPROJECT")
        layout.operator("omninoise.solid_procedural_node", icon="NODETREE")
        layout.operator("omninoise.solid_load_procedural", icon="IMPORT")
        layout.operator("omninoise.solid_save_procedural", icon="EXPORT")
        layout.separator()
        layout.operator("omninoise.bake_volume", icon="VOLUME_DATA")
        layout.operator("omninoise.bake_image", icon="IMAGE_DATA")


def _image_menu(self, context):
    self.layout.separator()
    self.layout.menu(OMNINOISE_MT_image.bl_idname, icon="TEXTURE")


def _add_menu(self, context):
    self.layout.menu(OMNINOISE_MT_add.bl_idname, icon="TEXTURE")


def _object_menu(self, context):
    self.layout.separator()
    self.layout.menu(OMNINOISE_MT_object.bl_idname, icon="TEXTURE")


def _render_menu(self, context):
    self.layout.separator()
    self.layout.operator("omninoise.run_job", text="Run Bake Job...", icon="PLAY")
    self.layout.operator("omninoise.save_job", text="Save Noise Bake as Job...", icon="EXPORT")
    self.layout.operator("omninoise.neural_save_job", text="Save Neural Bake as Job...", icon="EXPORT")
    self.layout.operator("omninoise.solid_save_job", text="Save Solid Bake as Job...", icon="EXPORT")


#: Blender menu -> the entry this module appends to it
APPENDED = {"IMAGE_MT_image": _image_menu, "VIEW3D_MT_add": _add_menu, "VIEW3D_MT_object": _object_menu,
            "TOPBAR_MT_render": _render_menu}
MENUS = (OMNINOISE_MT_image, OMNINOISE_MT_add, OMNINOISE_MT_object)
classes = MENUS


def attach():
    for name, draw in APPENDED.items():
        getattr(bpy.types, name).append(draw)


def detach():
    for name, draw in APPENDED.items():
        getattr(bpy.types, name).remove(draw)
