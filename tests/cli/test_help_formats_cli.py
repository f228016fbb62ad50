"""Every file format a command reads is named in its --help (issue 19's
debt: the help strings listed extensions by hand and drifted from the
format table).

The reference is the command itself, not the table: each subcommand is
given an empty file of every extension keymesh names anywhere (its
unknown-format messages and its help), and an empty folder (DICOM) and an
empty `*.zarr` folder (Zarr). An extension counts as read when the command
accepts the file or refuses its content, not its format ("unknown ..."). Every extension so
read must appear in the help line of the command's input, and every volume
format `contour --memory-limit` streams in that option's help line.
"""
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish, tempdir  # noqa: E402

D = tempdir()
EXT = re.compile(r"(?<!\w)\.[a-z][a-z0-9]*(?:\.gz)?\b")
# The arguments each command needs beside its input to get as far as reading
# it (alternatives: convert keeps the kind, so its output must match).
COMMANDS = {
    "contour": [["--iso", "1", "-o", "OUT.vtp"]],
    "pipeline": [["--iso", "1", "-o", "OUT.vtp"]],
    "tetrahedralize": [["-o", "OUT.vtu"]],
    "labels": [["-o", "OUT.vtp"]],
    "subdivide": [["-o", "OUT.vtp"], ["-o", "OUT.vtu"]],
    "check": [[]],
    "quality": [[]],
    "dual": [["-o", "OUT.vtp"]],
    "convert": [["-o", "OUT.vtp"], ["-o", "OUT.vtu"], ["-o", "OUT.nrrd"]],
    "info": [[]],
}
# What a command says of an input it has no reader for (or not with these arguments).
NOT_READ = ("unknown", "cannot be read plane by plane", "needs --dims", "keeps the kind", "subdivides into",
            "not a volume")


def km(*args):
    p = subprocess.run([os.path.abspath(KEYMESH), *args], capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=60,
                       cwd=D)
    assert p.returncode >= 0, f"keymesh {args}: signal {-p.returncode}"
    return p


def help_line(command, option):
    """The help text of one option (its line and its wrapped continuation)."""
    text = km(command, "--help").stdout
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if re.match(r"\s+" + re.escape(option) + r"\b", line):
            out = line
            for more in lines[i + 1:]:
                if not more.startswith("  " * 8):
                    break
                out += " " + more.strip()
            return out
    raise AssertionError(f"keymesh {command} --help has no line for {option}:\n{text}")


def candidate_extensions():
    """Every extension keymesh names: its unknown-format messages (which
    list the table's) and every help."""
    texts = [km("info", "x.zzz").stderr, km("check", "x.zzz").stderr, km("contour", "x.zzz", "--iso", "1", "-o",
                                                                         "o.vtp", "--memory-limit", "1M").stderr]
    texts += [km(c, "--help").stdout for c in COMMANDS]
    found = set()
    for t in texts:
        found.update(EXT.findall(t.lower()))
    found.discard(".zzz")
    return sorted(found)


def reads(command, path, extra=()):
    """Whether `command` tries to read `path` (its refusal is about the
    file's content, not about the format)."""
    out = os.path.join(D, "out_" + command + "_" + os.path.basename(path.rstrip("/")))  # one per probe
    for alternative in COMMANDS[command]:
        args = [a.replace("OUT", out) for a in alternative]
        p = km(command, path, *args, *extra)
        if p.returncode == 0:  # an empty mesh (an empty .obj is one)
            return True
        line = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
        if not any(s in line for s in NOT_READ):
            return True
    return False


def empty(name):
    path = os.path.join(D, name)
    if name.endswith("/"):
        os.makedirs(path, exist_ok=True)
    else:
        open(path, "wb").close()
    return path


def inputs_named_in_help():
    extensions = candidate_extensions()
    assert {".ply", ".vtp", ".nrrd", ".vtu"} <= set(extensions), extensions
    folders = {"DICOM": empty("series/"), "Zarr": empty("array.zarr/")}
    probes = {e: empty("probe" + e) for e in extensions}
    with ThreadPoolExecutor(4) as pool:  # some 200 short runs
        answers = {(c, e): pool.submit(reads, c, path) for c in COMMANDS for e, path in probes.items()}
    for command in COMMANDS:
        text = help_line(command, {"check": "mesh", "quality": "mesh", "info": "file"}.get(command, "input"))
        read = [e for e in extensions if answers[(command, e)].result()]
        assert read, f"keymesh {command} reads no extension at all"
        missing = [e for e in read if e not in EXT.findall(text.lower())]
        assert not missing, f"keymesh {command} reads {missing} but its help does not say so: {text}"
        for name, folder in folders.items():
            if reads(command, folder):
                assert name in text, f"keymesh {command} reads a {name} folder but its help does not say so: {text}"


def streamed_inputs_named_in_help():
    text = help_line("contour", "--memory-limit")
    named = EXT.findall(text.lower())
    for e in candidate_extensions():
        extra = ["--memory-limit", "1M"] + (["--dims", "2", "2", "2", "--type", "uint8"] if e == ".raw" else [])
        if reads("contour", empty("probe" + e), extra):
            assert e in named, f"contour --memory-limit streams {e} but its help does not say so: {text}"
    for name, folder in (("DICOM", "series/"), ("Zarr", "array.zarr/")):
        assert reads("contour", empty(folder), ["--memory-limit", "1M"])
        assert name in text, f"contour --memory-limit streams a {name} folder but its help does not say so: {text}"


check("every format a command reads is named in its input's --help", inputs_named_in_help)
check("every format contour --memory-limit streams is named in its --help", streamed_inputs_named_in_help)
finish()
