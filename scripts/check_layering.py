#!/usr/bin/env python3
"""Fails on an include that climbs the layers, or on torch outside the folders that hide it.

Layers, lowest first (docs/architecture.md):
    core -> integrators -> latent -> autodiff -> vae -> refiner -> pipeline -> apps | python
A file may include its own folder and any folder below it. Tests in tests/<folder>/ follow their
folder's rule. Only vae/ and refiner/ .cpp files (and their *_torch.h headers) may include torch:
every other header stays torch-free, so core and the renderers build and start without libtorch.

The CMake targets already refuse an include of a folder they do not link (each exposes only its
own headers); this check also catches an include that is linked but points the wrong way, and
runs without a build. Exit 0 when clean, 1 with one line per violation.
"""
import os
import re
import sys

LAYERS = ["core", "integrators", "latent", "autodiff", "vae", "refiner", "pipeline", "apps"]
RANK = {name: i for i, name in enumerate(LAYERS)}
RANK["python"] = RANK["apps"]  # the Python module sits beside the CLI: both call pipeline/, neither the other
TORCH_FOLDERS = {"vae", "refiner"}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)
SOURCE_EXT = (".h", ".hpp", ".cpp", ".cc")


def folder_of(rel_path):
    """The layer a source file belongs to (tests/<layer>/... counts as <layer>), or None."""
    parts = rel_path.split(os.sep)
    if parts[0] == "tests" and len(parts) > 2:
        parts = parts[1:]
    if parts[0] == "python":
        return "python"
    return parts[0] if parts[0] in RANK else None


def torch_allowed(rel_path, layer):
    name = os.path.basename(rel_path)
    if rel_path.startswith("tests" + os.sep):
        return layer in TORCH_FOLDERS or layer in ("pipeline", "apps")
    return layer in TORCH_FOLDERS and (name.endswith(".cpp") or name.endswith("_torch.h") or name == "refiner_net.h")


def violations(root):
    found = []
    for top in LAYERS + ["python", "tests"]:
        for dirpath, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith(SOURCE_EXT):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root)
                layer = folder_of(rel)
                if layer is None:
                    continue
                with open(path, encoding="utf-8", errors="replace") as f:
                    text = f.read()
                for m in INCLUDE.finditer(text):
                    bracket, target = m.group(1), m.group(2)
                    line = text.count("\n", 0, m.start()) + 1
                    if bracket == "<" and target.split("/")[0] in ("torch", "ATen", "c10"):
                        if not torch_allowed(rel, layer):
                            found.append(f"{rel}:{line}: includes <{target}>: torch stays inside vae/ and refiner/ .cpp files")
                        continue
                    head = target.split("/")[0]
                    if bracket == '"' and head in RANK and RANK[head] > RANK[layer]:
                        found.append(f"{rel}:{line}: {layer}/ includes \"{target}\": {head}/ is above {layer}/ "
                                     f"({' -> '.join(LAYERS)})")
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    found = violations(root)
    for v in found:
        print(v)
    if found:
        print(f"{len(found)} include(s) against the layering")
        return 1
    print("layering: every include points down or sideways")
    return 0


if __name__ == "__main__":
    sys.exit(main())
