"""The add-on's import rules, read from its source (ast) and checked by a plain Python, no Blender:

- three packages under addon/ndfbake, each importing only those before it: core (no bpy, importable
  by a plain Python), shading (Blender's data), blender (the bake as Blender runs it, the UI);
- no circle among the modules, imports inside functions included;
- importing the package itself imports nothing (register() imports what it needs);
- no module over MAX_LINES lines.

Prints the import graph between packages. Run: python3 tests/tools/test_addon_imports.py
"""
import ast
import os
import subprocess
import sys

ADDON = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "addon"))
PACKAGE = "ndfbake"
LAYERS = ("core", "shading", "blender")  # each may import the ones before it
MAX_LINES = 420                         # "about 400": a module that grows past it is split


def modules():
    """{'ndfbake.core.native': path, ...}, packages' __init__ as the package's name."""
    found = {}
    for folder, _, names in os.walk(os.path.join(ADDON, PACKAGE)):
        for name in names:
            if name.endswith(".py"):
                parts = os.path.relpath(os.path.join(folder, name), ADDON)[:-3].split(os.sep)
                if parts[-1] == "__init__":
                    parts.pop()
                found[".".join(parts)] = os.path.join(folder, name)
    return found


def imports(name, path, known):
    """(module-level, inside functions): the modules `name` imports, ndfbake's resolved and bpy."""
    tree = ast.parse(open(path, encoding="utf-8").read())
    package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
    top, nested = set(), set()
    functions = {id(n) for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                 for n in ast.walk(f)}
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            for alias in node.names:  # `from . import x` names a module; `from .x import y` a name in x
                candidate = base + "." + alias.name
                targets.append(candidate if candidate in known else base)
        for target in targets:
            if target == "bpy" or target.startswith("bpy.") or target.startswith(PACKAGE):
                (nested if id(node) in functions else top).add("bpy" if target.startswith("bpy") else target)
    return top, nested


def layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else None


def main():
    known = modules()
    failures = []
    graph = {}
    for name, path in sorted(known.items()):
        top, nested = imports(name, path, known)
        graph[name] = (top | nested) - {"bpy"}
        own = layer(name)
        if name == PACKAGE and top:
            failures.append("importing %s imports %s" % (name, sorted(top)))
        if own == "core" and "bpy" in top | nested:
            failures.append("%s (core) imports bpy" % name)
        for target in (top | nested) - {"bpy", name}:
            other = layer(target)
            if own and other and LAYERS.index(other) > LAYERS.index(own):
                failures.append("%s (%s) imports %s (%s)" % (name, own, target, other))
        lines = sum(1 for _ in open(path, encoding="utf-8"))
        if lines > MAX_LINES:
            failures.append("%s has %d lines (at most %d)" % (name, lines, MAX_LINES))

    # Circles: a depth-first search over every import, functions' included.
    state = {}

    def visit(module, stack):
        state[module] = "open"
        for target in sorted(graph.get(module, ())):
            if target == module or target not in graph:
                continue
            if state.get(target) == "open":
                circle = stack[stack.index(target):] + [target]
                failures.append("circle: %s" % " -> ".join(circle))
            elif target not in state:
                visit(target, stack + [target])
        state[module] = "done"
    for module in sorted(graph):
        if module not in state:
            visit(module, [module])

    # core in a plain Python, bpy made unimportable.
    core = sorted(m for m in known if layer(m) == "core")
    script = "import sys; sys.modules['bpy'] = None; sys.path.insert(0, %r)\n" % ADDON + "".join(
        "import %s\n" % m for m in core)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    if run.returncode != 0:
        failures.append("core does not import without bpy: %s" % run.stderr.strip().splitlines()[-1:])

    edges = {}
    for module, targets in graph.items():
        for target in targets:
            a, b = layer(module) or module, layer(target) or target
            if a != b:
                edges[(a, b)] = edges.get((a, b), 0) + 1
    print("modules: %s" % ", ".join("%s %d" % (pkg, sum(layer(m) == pkg for m in known)) for pkg in LAYERS))
    print("imports between packages: %s" % ", ".join("%s -> %s (%d)" % (a, b, n) for (a, b), n in sorted(edges.items())))
    print("core imported by a plain Python without bpy: %s" % ("yes" if run.returncode == 0 else "no"))
    for failure in failures:
        print("FAIL " + failure)
    print("%s test_addon_imports (%d modules)" % ("FAIL" if failures else "PASS", len(known)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
