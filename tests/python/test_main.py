"""python -m keymesh mirrors the keymesh command: same output, messages and exit codes."""
import os
import subprocess
import sys

import pytest

KEYMESH = os.environ.get("KEYMESH")
pytestmark = pytest.mark.skipif(not KEYMESH, reason="KEYMESH (the CLI) is not set")


def run(args, module):
    # the command as a user on PATH runs it: argv[0] is "keymesh" (the usage line shows it)
    if module:
        return subprocess.run([sys.executable, "-m", "keymesh"] + args, capture_output=True, text=True)
    return subprocess.run(["keymesh"] + args, executable=KEYMESH, capture_output=True, text=True)


@pytest.mark.parametrize("args", [
    ["--help"],
    ["contour", "no-such-file.vti", "-o", "x.vtp", "--iso", "1"],            # exit 1
    ["contour", "--iso", "nan", "in.vti", "-o", "x.vtp"],                    # exit 2
    ["tetrahedralize", "--scheme", "7", "in.vti", "-o", "t.vtu"],            # exit 2
])
def test_same_as_the_command(args, tmp_path):
    os.chdir(tmp_path)
    ours, theirs = run(args, True), run(args, False)
    assert ours.returncode == theirs.returncode
    assert ours.stdout == theirs.stdout and ours.stderr == theirs.stderr


def test_writes_what_the_command_writes(tmp_path):
    a = run(["generate", "sphere", "--size", "12", "-o", str(tmp_path / "a.vti")], True)
    b = run(["generate", "sphere", "--size", "12", "-o", str(tmp_path / "b.vti")], False)
    assert a.returncode == b.returncode == 0
    assert (tmp_path / "a.vti").read_bytes() == (tmp_path / "b.vti").read_bytes()
