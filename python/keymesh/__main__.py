"""python -m keymesh ...: the `keymesh` command, unchanged.

Runs the keymesh executable in place of this interpreter (os.execv), so its
options, messages on stderr, output files and exit codes (0 success, 1 bad
input, 2 bad usage) are the command's own. The executable is looked up as:
$KEYMESH; keymesh/bin/keymesh inside this package (what `pip install .`
puts there); the build tree's build/keymesh next to build/python/keymesh;
then `keymesh` on PATH.
"""
import os
import shutil
import sys


def find_executable():
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.environ.get("KEYMESH"),
                  os.path.join(here, "bin", "keymesh"),
                  os.path.join(os.path.dirname(os.path.dirname(here)), "keymesh"),
                  shutil.which("keymesh")]
    for path in candidates:
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def main(argv=None):
    args = sys.argv[1:] if argv is None else list(argv)
    exe = find_executable()
    if exe is None:
        sys.stderr.write("keymesh: the keymesh executable was not found (set KEYMESH=/path/to/keymesh, "
                         "or install with `pip install .`, which ships it in the package)\n")
        return 1
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(exe, ["keymesh"] + args)
    return 1  # not reached


if __name__ == "__main__":
    sys.exit(main())
