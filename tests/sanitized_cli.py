"""The short sanitized run of `make test` (issue 11): the `keymesh` command
built with AddressSanitizer + UndefinedBehaviorSanitizer (build-fuzz: the clang build that also makes the fuzzers)
runs the hostile-input, contour and formats (DICOM, Zarr, glTF) CLI tests,
then reads every file of the fuzz seed corpus and of tests/fuzz/regressions
with `keymesh info` (the DICOM and Zarr inputs unpacked into their folders):
each must end with exit 0 or 1 and no sanitizer report.
`make sanitize` is the whole suite under ASan/UBSan and TSan.

Usage: sanitized_cli.py build-fuzz/keymesh (with ASAN_OPTIONS set)."""
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
KEYMESH = os.path.abspath(sys.argv[1])
# A sanitizer report exits 99, distinct from keymesh's own 1 and 2.
env = dict(os.environ)
for var in ("ASAN_OPTIONS", "UBSAN_OPTIONS"):
    env[var] = (env.get(var, "") + ":exitcode=99").lstrip(":")
env.setdefault("KEYMESH_HUGE_PAGES", "0")

# The longest first.
SCRIPTS = ("cli/test_hardening.py", "cli/test_hardening_io.py", "cli/test_formats_cli.py", "cli/test_contour_cli.py")


def run_script(script):
    return subprocess.run([sys.executable, os.path.join(HERE, script), KEYMESH], env=env, stdin=subprocess.DEVNULL,
                          capture_output=True, text=True, timeout=900)


failed = []
# The scripts, JOBS at a time (each is mostly one process at a time: two at
# once keep CI's two cores busy), beside the corpus replay below; their
# reports are printed in this order once the replay is done.
pool = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, int(os.environ.get("JOBS") or 1)))
script_runs = [(script, pool.submit(run_script, script)) for script in SCRIPTS]


def report_scripts():
    for script, future in script_runs:
        p = future.result()
        last = (p.stdout.strip().splitlines() or ["(no output)"])[-1]
        print(f"sanitized: {script}: {last}")
        if p.returncode != 0:
            failed.append(script)
            print(p.stdout[-4000:], p.stderr[-4000:])


EXTENSIONS = {"den": ".den", "legacy_vtk": ".vtk", "nifti": ".nii", "nrrd": ".nrrd", "obj": ".obj", "ply": ".ply",
              "stl": ".stl", "vti": ".vti", "vtp": ".vtp", "vtu": ".vtu"}  # raw: headerless, nothing to parse
# Folder formats: inputs pack a folder (tests/fuzz/folder_input.hpp), unpacked here into one of this name.
FOLDERS = {"dicom": "series", "zarr": "in.zarr"}
SAFE_NAME = re.compile(r"^[A-Za-z0-9._-]+(/[A-Za-z0-9._-]+){0,3}$")


def unpack_folder(data, root):
    """The folder a packed fuzz input holds, as folder_input.hpp makes it;
    returns the path to read (the "@open" sub-folder when one is named)."""
    if os.path.exists(root):
        shutil.rmtree(root)
    os.makedirs(root)
    start = data.find(b"KMFILE:")
    if start < 0:
        return root
    target = root
    records = data[start + len(b"KMFILE:"):].split(b"\nKMFILE:")
    for record in records[:64]:
        name, newline, body = record.partition(b"\n")
        name = name.decode("latin-1")
        if not newline:
            break
        safe = len(name) <= 64 and SAFE_NAME.match(name) and not any(p in (".", "..") for p in name.split("/"))
        if name == "@open":
            if SAFE_NAME.match(body.decode("latin-1")) and len(body) <= 64:
                target = os.path.join(root, body.decode("latin-1"))
            continue
        path = os.path.join(root, name)
        if not safe or os.path.isdir(path):
            continue
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "wb") as f:
                f.write(body)
        except OSError:  # a part of the path is a file already
            continue
    return target


replayed = 0
with tempfile.TemporaryDirectory(prefix="keymesh-sanitized-") as tmp:
    for root in (os.path.join(HERE, "fuzz", "corpus"), os.path.join(HERE, "fuzz", "regressions")):
        for folder, _, files in sorted(os.walk(root)):
            ext = EXTENSIONS.get(os.path.basename(folder))
            leaf = FOLDERS.get(os.path.basename(folder))
            if not ext and not leaf:
                continue
            for name in sorted(files):
                src = os.path.join(folder, name)
                # `info` picks the reader by extension: give the file its format's.
                path = src
                if leaf:
                    with open(src, "rb") as f:
                        path = unpack_folder(f.read(), os.path.join(tmp, "folder", leaf))
                elif not (src.endswith(ext) or src.endswith(ext + ".gz")):
                    path = os.path.join(tmp, "input" + ext)
                    shutil.copyfile(src, path)
                p = subprocess.run([KEYMESH, "info", path], env=env, stdin=subprocess.DEVNULL, capture_output=True,
                                   text=True, timeout=120)
                replayed += 1
                if p.returncode not in (0, 1) or "Sanitizer" in p.stderr or "runtime error" in p.stderr:
                    failed.append(src)
                    print(f"sanitized: {src}: exit {p.returncode}\n{p.stderr[-3000:]}")
print(f"sanitized: {replayed} corpus and regression files read by `keymesh info`")
report_scripts()
if failed:
    print(f"sanitized: FAILED: {', '.join(failed)}")
    sys.exit(1)
print("sanitized: clean")
