"""The short sanitized run of `make test` (issue 11): the `keymesh` command
built with AddressSanitizer + UndefinedBehaviorSanitizer (build-fuzz: the clang build that also makes the fuzzers)
runs the hostile-input, contour and formats (DICOM, Zarr, glTF) CLI tests,
then reads every file of the fuzz seed corpus and of tests/fuzz/regressions
with `keymesh info`: each must end with exit 0 or 1 and no sanitizer report.
`make sanitize` is the whole suite under ASan/UBSan and TSan.

Usage: sanitized_cli.py build-fuzz/keymesh (with ASAN_OPTIONS set)."""
import os
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

failed = []
for script in ("cli/test_hardening.py", "cli/test_contour_cli.py", "cli/test_formats_cli.py"):
    p = subprocess.run([sys.executable, os.path.join(HERE, script), KEYMESH], env=env, stdin=subprocess.DEVNULL,
                       capture_output=True, text=True, timeout=900)
    last = (p.stdout.strip().splitlines() or ["(no output)"])[-1]
    print(f"sanitized: {script}: {last}")
    if p.returncode != 0:
        failed.append(script)
        print(p.stdout[-4000:], p.stderr[-4000:])

EXTENSIONS = {"den": ".den", "legacy_vtk": ".vtk", "nifti": ".nii", "nrrd": ".nrrd", "obj": ".obj", "ply": ".ply",
              "stl": ".stl", "vti": ".vti", "vtp": ".vtp", "vtu": ".vtu"}  # raw: headerless, nothing to parse
replayed = 0
with tempfile.TemporaryDirectory(prefix="keymesh-sanitized-") as tmp:
    for root in (os.path.join(HERE, "fuzz", "corpus"), os.path.join(HERE, "fuzz", "regressions")):
        for folder, _, files in sorted(os.walk(root)):
            ext = EXTENSIONS.get(os.path.basename(folder))
            if not ext:
                continue
            for name in sorted(files):
                src = os.path.join(folder, name)
                # `info` picks the reader by extension: give the file its format's.
                path = src
                if not (src.endswith(ext) or src.endswith(ext + ".gz")):
                    path = os.path.join(tmp, "input" + ext)
                    shutil.copyfile(src, path)
                p = subprocess.run([KEYMESH, "info", path], env=env, stdin=subprocess.DEVNULL, capture_output=True,
                                   text=True, timeout=120)
                replayed += 1
                if p.returncode not in (0, 1) or "Sanitizer" in p.stderr or "runtime error" in p.stderr:
                    failed.append(src)
                    print(f"sanitized: {src}: exit {p.returncode}\n{p.stderr[-3000:]}")
print(f"sanitized: {replayed} corpus and regression files read by `keymesh info`")
if failed:
    print(f"sanitized: FAILED: {', '.join(failed)}")
    sys.exit(1)
print("sanitized: clean")
