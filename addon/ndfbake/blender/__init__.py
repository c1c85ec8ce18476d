"""The bake as Blender runs it: prepare, the native step, finish and revert (bake, bake_revert),
the lobe folders' lifetime across saves and sessions (lobe_folders), and the user's side: the
operators, the panel and its cached state, the handlers and registration. Imports core/ and
shading/."""
