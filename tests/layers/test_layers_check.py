"""The layering check (cmake/check_layers.cmake) can fail: fed small fake
source trees, it passes a tree whose includes follow cmake/layers.cmake and
refuses, naming the file and both layers, every tree that adds one include
the table does not allow (a lower layer including a higher one, a sibling, a
private header, a "../" include, a directory that is no layer).

    python3 tests/layers/test_layers_check.py [CMAKE]
"""
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import SOURCE_DIR, check, finish, tempdir  # noqa: E402

CMAKE = sys.argv[1] if len(sys.argv) > 1 else "cmake"
SCRIPT = os.path.join(SOURCE_DIR, "cmake", "check_layers.cmake")
D = tempdir()

# A tree that keeps to the table: every include goes to the same layer or to
# one the table lists for it.
CLEAN = {
    "include/keymesh/core/id.hpp": "#pragma once\n",
    "include/keymesh/mesh/grid.hpp": '#pragma once\n#include "keymesh/core/id.hpp"\n',
    "src/mesh/grid.cpp": '#include "keymesh/mesh/grid.hpp"\n#include "grid_rows.hpp"\n#include <vector>\n',
    "src/mesh/grid_rows.hpp": '#pragma once\n#include "keymesh/core/id.hpp"\n',
    "src/generate/contour/contour.cpp": '#include "keymesh/analyze/topology.hpp"\n#include "keymesh/mesh/grid.hpp"\n',
    "src/backend/contour.cpp": '#include "keymesh/cuda/backend.hpp"\n#include "keymesh/generate/contour/contour.hpp"\n',
    "src/cli/main.cpp": '#include "keymesh/backend/contour.hpp"\n#include "command.hpp"\n',
    "python/src/module.cpp": '#include <pybind11/pybind11.h>\n#include "keymesh/io/mesh_io.hpp"\n',
    # Not includes: a commented-out line and a string.
    "src/core/notes.cpp": '// #include "keymesh/io/mesh_io.hpp"\nconst char* s = "#include \\"keymesh/io/x.hpp\\"";\n',
}


def make_tree(name, extra):
    root = os.path.join(D, name)
    shutil.rmtree(root, ignore_errors=True)
    for path, text in {**CLEAN, **extra}.items():
        os.makedirs(os.path.dirname(os.path.join(root, path)), exist_ok=True)
        with open(os.path.join(root, path), "w") as f:
            f.write(text)
    return root


def run_check(root, stamp=None):
    args = [CMAKE, f"-DKEYMESH_TREE={root}"] + ([f"-DKEYMESH_STAMP={stamp}"] if stamp else []) + ["-P", SCRIPT]
    return subprocess.run(args, capture_output=True, text=True, timeout=120)


def expect_refused(name, extra, *phrases):
    p = run_check(make_tree(name, extra))
    assert p.returncode != 0, f"{name}: the check passed a tree with {list(extra)}\n{p.stdout}{p.stderr}"
    for phrase in phrases:
        assert phrase in p.stderr, f"{name}: {phrase!r} not in the check's message:\n{p.stderr}"


def clean_tree_passes():
    stamp = os.path.join(D, "clean.checked")
    p = run_check(make_tree("clean", {}), stamp)
    assert p.returncode == 0, p.stderr
    assert os.path.exists(stamp), "no stamp written on success"


def the_project_tree_passes():
    p = run_check(SOURCE_DIR)
    assert p.returncode == 0, p.stderr


# Trees that add one file the table does not allow: (what it shows, tree name,
# the file added, phrases the check's message must hold).
REFUSED = [
    ("a public header including a higher layer is refused", "upward-header",
     {"include/keymesh/core/bad.hpp": "#pragma once\n#include <keymesh/mesh/grid.hpp>\n"},
     ["include/keymesh/core/bad.hpp", "layer core may not use mesh"]),
    ("a private header in src/<layer>/ counts as that layer", "private",
     {"src/keyreduce/plan.hpp": '#pragma once\n#include "keymesh/generate/contour/contour.hpp"\n'},
     ["src/keyreduce/plan.hpp", "layer keyreduce may not use generate"]),
    # The cycle issue 16 removed: generate naming the CUDA backend.
    ("generate including the CUDA backend is refused", "gpu",
     {"src/generate/contour/contour.cpp": '#include "keymesh/cuda/backend.hpp"\n'},
     ["src/generate/contour/contour.cpp", "layer generate may not use cuda"]),
    ("siblings (io, analyze) may not include each other", "sibling",
     {"src/io/reader.cpp": '#include "keymesh/analyze/topology.hpp"\n'},
     ["src/io/reader.cpp", "layer io may not use analyze"]),
    ("an indented '#  include' is read", "indented",
     {"src/core/x.cpp": '#if 1\n  #  include "keymesh/io/mesh_io.hpp"\n#endif\n'},
     ["src/core/x.cpp", "layer core may not use io"]),
    ("a '../' include is refused", "relative",
     {"src/mesh/y.cpp": '#include "../generate/contour_rows.hpp"\n'},
     ["src/mesh/y.cpp", "../generate/contour_rows.hpp"]),
    ("a directory that is no layer is refused", "unknown",
     {"src/widgets/w.cpp": "int w;\n"}, ["src/widgets/w.cpp", "'widgets' is not a layer"]),
    ("every violation is named, not just the first", "two",
     {"src/core/a.cpp": '#include "keymesh/parallel/for_each.hpp"\n',
      "include/keymesh/parallel/b.hpp": '#include "keymesh/keyreduce/groups.hpp"\n'},
     ["src/core/a.cpp", "include/keymesh/parallel/b.hpp", "2 file(s) or include(s)"]),
]


def architecture_shows_the_table():
    # docs/ARCHITECTURE.md's "Layers" table lists the layers of cmake/layers.cmake in its order,
    # each with the layers the table lets it use.
    with open(os.path.join(SOURCE_DIR, "cmake", "layers.cmake")) as f:
        text = f.read()
    order = re.search(r"set\(KEYMESH_LAYERS ([^)]*)\)", text).group(1).split()
    uses = {m.group(1): m.group(2).replace('"', "").split()
            for m in re.finditer(r"set\(KEYMESH_LAYER_USES_(\w+)\s+([^)]*)\)", text)}
    with open(os.path.join(SOURCE_DIR, "docs", "ARCHITECTURE.md")) as f:
        notes = f.read()
    section = notes.split("\n## Layers\n", 1)[1].split("\n## ", 1)[0]
    rows = [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in section.splitlines() if line.startswith("| ") and not line.startswith(("| layer", "| ---"))]
    assert [r[0] for r in rows] == order, ([r[0] for r in rows], order)
    for layer, _, may_use in rows:
        if may_use == "—":
            shown = []
        elif may_use.startswith("every layer but "):
            shown = [x for x in order if x not in (layer, may_use.split()[-1])]
        else:
            shown = may_use.split()
        assert shown == uses[layer], (layer, shown, uses[layer])


check("a tree that keeps to the table passes and gets its stamp", clean_tree_passes)
check("the project's own tree passes", the_project_tree_passes)
for title, name, extra, phrases in REFUSED:
    check(title, lambda name=name, extra=extra, phrases=phrases: expect_refused(name, extra, *phrases))
check("docs/ARCHITECTURE.md's Layers table is cmake/layers.cmake's", architecture_shows_the_table)
shutil.rmtree(D, ignore_errors=True)
finish()
