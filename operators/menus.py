"""Object ▸ Curved Fold: one submenu with every Curved Fold operator, in the order of work.

Blender's convention (its bundled add-ons do the same): every operator is reachable from a menu, so F3 menu search
finds it, and greyed out with its poll message where it does not apply. The sidebar (N ▸ Curved Fold) has the same
operators next to the settings they use.
"""

from __future__ import annotations

import bpy


class VIEW3D_MT_curved_fold(bpy.types.Menu):
    """Curved Fold: import, crease roles, fold, live re-fold, pins and glue, bake, colors and export"""

    bl_idname = "VIEW3D_MT_curved_fold"
    bl_label = "Curved Fold"

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        layout.operator("curved_fold.import_pattern", text="Import Crease Pattern…", icon="IMPORT")
        layout.separator()
        layout.operator_menu_enum("curved_fold.set_crease_role", "role", text="Set Crease Role")
        layout.operator_menu_enum("curved_fold.select_by_role", "role", text="Select by Crease Role")
        layout.separator()
        layout.operator("curved_fold.fold", icon="MOD_SIMPLEDEFORM")
        layout.operator("curved_fold.refold", icon="FILE_REFRESH")
        layout.operator("curved_fold.toggle_live", icon="REC")
        layout.separator()
        layout.operator("curved_fold.add_pin_hooks", icon="EMPTY_AXIS")
        layout.operator("curved_fold.glue_selected", icon="AUTOMERGE_ON")
        layout.operator("curved_fold.clear_glue", icon="X")
        layout.separator()
        layout.operator("curved_fold.bake", icon="RENDER_ANIMATION")
        layout.operator("curved_fold.clear_bake", icon="X")
        layout.operator_menu_enum("curved_fold.show_colours", "kind", text="Show Fold Colors")
        layout.separator()
        layout.operator("curved_fold.export_folded", text="Export Folded Mesh…", icon="EXPORT")
        layout.operator("curved_fold.export_pattern_svg", text="Export Crease Pattern SVG…", icon="FILE_IMAGE")


def _menu(self: bpy.types.Menu, context: bpy.types.Context) -> None:
    self.layout.separator()
    self.layout.menu(VIEW3D_MT_curved_fold.bl_idname)


CLASSES = (VIEW3D_MT_curved_fold,)


def register_extra() -> None:
    bpy.types.VIEW3D_MT_object.append(_menu)


def unregister_extra() -> None:
    bpy.types.VIEW3D_MT_object.remove(_menu)
