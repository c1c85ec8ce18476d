"""What a bake builds in Blender's data, and what it reads there: the material's normal-map chain
and bake record (material_scan), the material's node group (nodes, lobe_nodes, lod_nodes,
specular_split, group_node), the level of detail the scene's cameras need (scene_lod), the OSL
variant (osl_group) and what differs between Blender versions (blender_compat). Imports core/, never
blender/."""
