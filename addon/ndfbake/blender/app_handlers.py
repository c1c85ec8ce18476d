"""bpy.app.handlers entries a module of the add-on installs and removes as one set
(lobe_folders.py, panel_state.py). Removal also takes those an earlier load of the module left (a
reloaded add-on): they are matched by module and function name, not by identity."""
import bpy


def remove(module_name, handlers):
    """handlers: (bpy.app.handlers list name, function) pairs of the module `module_name`."""
    for name, handler in handlers:
        entries = getattr(bpy.app.handlers, name)
        for old in [h for h in entries if getattr(h, "__module__", None) == module_name
                    and h.__name__ == handler.__name__]:
            entries.remove(old)


def install(module_name, handlers):
    """Replaces the module's handlers (an earlier load's too) with these."""
    remove(module_name, handlers)
    for name, handler in handlers:
        getattr(bpy.app.handlers, name).append(handler)
