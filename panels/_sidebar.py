"""Where every Curved Fold panel sits: the 3D viewport's sidebar (N), tab "Curved Fold".

A mixin, as Blender's bundled add-ons share their panels' placement; modules starting with ``_`` are not scanned for
classes to register.
"""


class SidebarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Curved Fold"
