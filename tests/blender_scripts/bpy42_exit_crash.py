"""Minimal reproduction of the bpy 4.2.23 wheel crashing at interpreter exit (exit 139): a PropertyGroup
whose property has an update callback, registered and unregistered.  No OmniNoise code involved.
Run: python bpy42_exit_crash.py upd   (exits 139 on bpy 4.2.23; 0 on 5.0.1 and 5.2.3, and without "upd")."""
import sys, bpy
def upd(self, context): pass
class FOO_PG(bpy.types.PropertyGroup):
    a: bpy.props.FloatProperty(update=upd) if "upd" in sys.argv else bpy.props.FloatProperty()
    b: bpy.props.EnumProperty(items=[("A","A",""),("B","B","")]) if "enum" in sys.argv else bpy.props.IntProperty()
    c: bpy.props.StringProperty() if "str" in sys.argv else bpy.props.IntProperty()
bpy.utils.register_class(FOO_PG)
bpy.utils.unregister_class(FOO_PG)
print("ok")
