#!/usr/bin/env python3
"""Structure checks the build cannot make on its own.

1. No include cycle between source folders: folder A including a header of
   folder B while B (directly or through others) includes A's is a cycle.
2. No include across the library targets against their graph (pba_base,
   pba_yaml_guard, pba_plot <- pba_fem <- pba_atlas <- pba_solver, see
   solver/CMakeLists.txt), and from server/ and client_cli/ only the
   solver's public headers (pba/, pba_base's, the plots', and for the
   server the atlas pipeline's).
3. No function longer than MAX_FUNCTION_LINES lines (Universal Ctags finds
   the functions and their ends), outside generated code.

Prints each violation with the files that make it and exits 1 if there is
any, 0 otherwise. Run from anywhere: `python3 scripts/check_structure.py`
(--root DIR checks another tree laid out the same way).
"""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SOURCE_TREES = ["solver", "server", "client_cli", "proto", "tests"]
# Where a quoted include is looked up, after the including file's folder,
# in the order the compilers' include paths give.
INCLUDE_ROOTS = ["solver/include", "solver", "server", "client_cli", "proto", "tests"]
MAX_FUNCTION_LINES = 150
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def sources():
    for tree in SOURCE_TREES:
        for directory, _, files in os.walk(os.path.join(ROOT, tree)):
            for name in files:
                if name.endswith((".cc", ".h")):
                    yield os.path.relpath(os.path.join(directory, name), ROOT)


def resolve(including, header):
    for base in [os.path.dirname(including)] + INCLUDE_ROOTS:
        candidate = os.path.normpath(os.path.join(base, header))
        if os.path.isfile(os.path.join(ROOT, candidate)):
            return candidate
    return None  # generated (pba/v1/*.pb.h) or a system header


def folder_graph(files):
    """folder -> {folder it includes from -> [(file, header), ...]}"""
    graph = {}
    for path in files:
        here = os.path.dirname(path)
        with open(os.path.join(ROOT, path), encoding="utf-8") as text:
            for line in text:
                match = INCLUDE.match(line)
                if not match:
                    continue
                target = resolve(path, match.group(1))
                if target is None:
                    continue
                there = os.path.dirname(target)
                if there != here:
                    graph.setdefault(here, {}).setdefault(there, []).append((path, target))
    return graph


def strongly_connected(graph):
    """Tarjan's algorithm; returns the components with more than one folder."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]

    def visit(node):
        index[node] = low[node] = counter[0]
        counter[0] += 1
        stack.append(node)
        on_stack.add(node)
        for succ in graph.get(node, {}):
            if succ not in index:
                visit(succ)
                low[node] = min(low[node], low[succ])
            elif succ in on_stack:
                low[node] = min(low[node], index[succ])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10000)
    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


# Which library target owns a solver file: by folder, with the exceptions
# that split core/ and io/ between targets.
BASE_FILES = ("core/sha256", "core/atomic_write", "core/number_format", "core/exit_codes",
              "core/format", "core/cache_dir", "core/checksum_file", "atlas/structure_format")
PLOT_FILES = ("io/png_io", "io/bitmap_font", "io/line_plot")
FOLDER_TARGETS = {
    "fem": "pba_fem", "material": "pba_fem", "mesh": "pba_fem", "assembly": "pba_fem",
    "linear": "pba_fem", "signal": "pba_fem", "core": "pba_fem",
    "io": "pba_atlas", "atlas": "pba_atlas",
    "scene": "pba_solver", "analysis": "pba_solver", "explicit": "pba_solver",
    "results": "pba_solver", "api": "pba_solver",
}
# What each target may include (pba/ is the declarations every target shares).
MAY_INCLUDE = {
    "pba_base": {"pba_base", "pba/"},
    "pba_yaml_guard": {"pba_yaml_guard", "pba_base", "pba/"},
    "pba_plot": {"pba_plot", "pba_base", "pba/"},
    "pba_fem": {"pba_fem", "pba_base", "pba/"},
    "pba_atlas": {"pba_atlas", "pba_fem", "pba_plot", "pba_yaml_guard", "pba_base", "pba/"},
    "pba_solver": {"pba_solver", "pba_atlas", "pba_fem", "pba_plot", "pba_yaml_guard",
                   "pba_base", "pba/"},
    # Outside solver/: the public headers only.
    "server": {"pba_base", "pba_yaml_guard", "pba_plot", "pba/", "atlas public"},
    "client": {"pba_base", "pba_yaml_guard", "pba_plot", "pba/"},
}


def solver_target(path):
    """The target owning solver file `path`, "pba/" for the public
    declarations, None outside solver/."""
    if not path.startswith("solver/"):
        return None
    inner = os.path.splitext(path[len("solver/"):])[0]
    if inner.startswith("include/pba/"):
        return "pba/"
    if inner in BASE_FILES:
        return "pba_base"
    if inner == "core/yaml_guard":
        return "pba_yaml_guard"
    if inner in PLOT_FILES:
        return "pba_plot"
    return FOLDER_TARGETS.get(inner.split("/")[0])


def includer(path):
    if path.startswith("server/"):
        return "server"
    if path.startswith("client_cli/"):
        return "client"
    return solver_target(path)


def target_violations(files):
    found = []
    for path in sorted(files):
        who = includer(path)
        if who is None or who == "pba/":
            continue
        allowed = MAY_INCLUDE[who]
        with open(os.path.join(ROOT, path), encoding="utf-8") as text:
            for line in text:
                match = INCLUDE.match(line)
                target = match and resolve(path, match.group(1))
                owner = target and solver_target(target)
                if owner is None or owner in allowed:
                    continue
                if (who == "server" and owner == "pba_atlas" and
                        (target.startswith("solver/atlas/") or target == "solver/io/mesh_export.h")):
                    continue  # the atlas pipeline's public headers
                found.append(f"{path} ({who}) includes {target} ({owner})")
    return found


def long_functions(files):
    command = ["ctags", "-x", "--c++-kinds=f", "--fields=+ne", "--language-force=C++",
               "--_xformat=%{line}|%{end}|%{input}|%{name}"]
    output = subprocess.run(command + sorted(files), cwd=ROOT, check=True,
                            capture_output=True, text=True).stdout
    found = []
    for row in output.splitlines():
        first, last, path, name = row.split("|", 3)
        if not last:
            continue
        lines = int(last) - int(first) + 1
        if lines > MAX_FUNCTION_LINES:
            found.append((lines, f"{path}:{first}", name))
    return sorted(found, reverse=True)


def main():
    global ROOT
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=ROOT, help="the source tree (default: this checkout)")
    ROOT = os.path.abspath(parser.parse_args().root)
    files = list(sources())
    failures = 0
    graph = folder_graph(files)
    for component in strongly_connected(graph):
        failures += 1
        print("include cycle between folders: " + " <-> ".join(component))
        for source in component:
            for target in component:
                for path, header in graph.get(source, {}).get(target, [])[:3]:
                    print(f"  {path} includes {header}")
    for violation in target_violations(files):
        failures += 1
        print("include across targets: " + violation)
    for lines, where, name in long_functions(files):
        failures += 1
        print(f"function over {MAX_FUNCTION_LINES} lines: {name} ({lines} lines) at {where}")
    if failures:
        print(f"{failures} structure problem(s)")
        return 1
    print(f"structure: {len(files)} files, no include cycle between folders or across "
          f"targets, no function over {MAX_FUNCTION_LINES} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
