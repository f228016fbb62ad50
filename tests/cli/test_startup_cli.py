"""What a start of `keymesh` does before its command runs.

- GDCM is a module, libkeymesh_gdcm.so, opened by the first DICOM read and
  looked for beside the executable (its real file: a symlink to it works):
  a copy of the command without it reads every other format and refuses a
  DICOM series naming the missing file; with the module beside it, it reads
  the series as the build's command does.
- MPI is the module libkeymesh_mpi.so, opened only under an MPI launcher:
  a copy of the command without it refuses `mpirun -np 2` naming the file.
- The huge-page re-exec (core/huge_pages.hpp), seen through strace (skipped
  without it, and in sanitizer builds, which never re-exec): one re-exec of
  /proc/self/exe adding glibc.malloc.hugetlb=1 and the mark
  KEYMESH_HUGE_PAGES_REEXEC=1; none with KEYMESH_HUGE_PAGES=0 or with the
  tunable already set.
"""
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish, mpirun, run, tempdir  # noqa: E402

D = tempdir()
MODULE = "libkeymesh_gdcm.so"
MPI_MODULE = "libkeymesh_mpi.so"
KEYMESH_FILE = os.path.abspath(KEYMESH)
SANITIZED = any(k in os.environ for k in ("ASAN_OPTIONS", "TSAN_OPTIONS", "UBSAN_OPTIONS"))


def plain_env(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("GLIBC_TUNABLES", "KEYMESH_HUGE_PAGES", "KEYMESH_HUGE_PAGES_REEXEC")}
    env.update(extra)
    return env


def nrrd_volume():
    path = os.path.join(D, "small.nrrd")
    with open(path, "wb") as f:
        f.write(b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 3 2 2\nencoding: raw\n\n" + bytes(range(12)))
    return path


def dicom_series():
    try:
        import numpy as np
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
        from dicom_series import write_dicom_series
    except ImportError as e:
        return None, str(e)
    folder = os.path.join(D, "series")
    if not os.path.isdir(folder):
        write_dicom_series(folder, (np.arange(3 * 4 * 5).reshape(3, 4, 5) * 7).astype(np.int16))
    return folder, None


def copied_command(name, with_module):
    folder = os.path.join(D, name)
    os.makedirs(folder)
    shutil.copy2(KEYMESH, os.path.join(folder, "keymesh"))
    if with_module:
        shutil.copy2(os.path.join(os.path.dirname(KEYMESH_FILE), MODULE), os.path.join(folder, MODULE))
    return os.path.join(folder, "keymesh")


def info(command, path, expect):
    p = subprocess.run([command, "info", path], capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert p.returncode == expect, f"{command} info {path}: exit {p.returncode}\n{p.stdout}{p.stderr}"
    return p


def without_module_dicom_refused_by_name():
    series, why = dicom_series()
    alone = copied_command("alone", with_module=False)
    assert "dims 3 x 2 x 2" in info(alone, nrrd_volume(), 0).stdout  # no DICOM, no module needed
    if series is None:
        print(f"        (DICOM half skipped: {why})")
        return
    err = info(alone, series, 1).stderr
    assert os.path.join(D, "alone", MODULE) in err and "missing" in err, err
    assert err.count("\n") == 1, err  # one line, no crash


def module_found_beside_the_real_file():
    series, why = dicom_series()
    if series is None:
        print(f"        (skipped: {why})")
        return
    expected = run("info", series).stdout
    beside = copied_command("beside", with_module=True)
    assert info(beside, series, 0).stdout == expected
    link = os.path.join(D, "elsewhere", "keymesh")
    os.makedirs(os.path.dirname(link))
    os.symlink(beside, link)
    assert info(link, series, 0).stdout == expected


def without_mpi_module_mpirun_refused_by_name():
    alone = os.path.join(D, "alone", "keymesh")
    if not os.path.exists(alone):
        copied_command("alone", with_module=False)
    p = mpirun(2, "--version", expect=None, program=alone)
    assert p.returncode != 0, p.stdout
    message = f"keymesh: a run under an MPI launcher needs keymesh's module {os.path.join(D, 'alone', MPI_MODULE)}"
    # Every rank meets it alike: said once, by rank 0 (issue 34), no crash.
    assert p.stderr.count(message) == 1 and "missing" in p.stderr, p.stderr


def execs(env):
    """The execve calls of one `keymesh --version` (program, environment)."""
    log = os.path.join(D, "strace.log")
    p = subprocess.run(["strace", "-f", "-qq", "-s", "4096", "-v", "-e", "trace=execve", "-o", log, KEYMESH,
                        "--version"], env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0 and "keymesh" in p.stdout, p.stderr
    calls = [line for line in open(log) if "execve(" in line and "= 0" in line]
    return [(re.search(r'execve\("([^"]*)"', c).group(1), c) for c in calls]


def reexec_once_with_the_tunable():
    calls = execs(plain_env())
    assert len(calls) == 2, calls
    program, call = calls[1]
    assert program == "/proc/self/exe", calls
    assert '"GLIBC_TUNABLES=glibc.malloc.hugetlb=1"' in call and '"KEYMESH_HUGE_PAGES_REEXEC=1"' in call, call
    calls = execs(plain_env(GLIBC_TUNABLES="glibc.malloc.arena_max=2"))
    assert len(calls) == 2 and '"GLIBC_TUNABLES=glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1"' in calls[1][1]


def no_reexec_when_off_or_set():
    assert len(execs(plain_env(KEYMESH_HUGE_PAGES="0"))) == 1
    assert len(execs(plain_env(GLIBC_TUNABLES="glibc.malloc.hugetlb=0"))) == 1
    assert len(execs(plain_env(KEYMESH_HUGE_PAGES_REEXEC="1"))) == 1


check("GDCM module missing: other formats read, DICOM refused naming the file", without_module_dicom_refused_by_name)
check("GDCM module found beside the executable's real file (symlinked too)", module_found_beside_the_real_file)
if not shutil.which("mpirun") or not os.path.exists(os.path.join(os.path.dirname(KEYMESH_FILE), MPI_MODULE)):
    print("        (MPI module check skipped: no mpirun, or keymesh built without MPI)")
elif mpirun(2, expect=None, program=shutil.which("true") or "/bin/true").returncode != 0:
    print("        (MPI module check skipped: mpirun -np 2 true fails here)")
else:
    check("MPI module missing: mpirun refused naming the file, said once", without_mpi_module_mpirun_refused_by_name)
if SANITIZED:
    print("        (re-exec checks skipped: sanitizer builds never re-exec)")
elif not shutil.which("strace"):
    print("        (re-exec checks skipped: no strace)")
else:
    check("huge pages: one re-exec of /proc/self/exe adding the tunable and the mark", reexec_once_with_the_tunable)
    check("huge pages: no re-exec with KEYMESH_HUGE_PAGES=0, the tunable set, or the mark", no_reexec_when_off_or_set)
finish()
