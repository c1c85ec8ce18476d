"""The add-on's core: no bpy, importable and testable by a plain Python. The library's binding
(native), the bake's native step that runs off the main thread (bake_job) and a bake's folder and
file names (folder_names). Imports nothing from shading/ or blender/."""
