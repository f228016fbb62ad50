"""ctest entry for the Python module: pytest -q over tests/python.

Exits 77 (ctest: skipped) when pytest or numpy is missing or when the
extension was not built into PYTHONPATH; otherwise pytest's exit status.
"""
import importlib.util
import os
import sys

if __name__ == "__main__":
    # Not this folder's source package (it has no extension): the build tree's, via PYTHONPATH.
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path = [p for p in sys.path if os.path.abspath(p or ".") != here]
    for needed in ("pytest", "numpy"):
        if importlib.util.find_spec(needed) is None:
            print(f"skipped: {needed} is not installed for {sys.executable}")
            sys.exit(77)
    try:
        import keymesh  # noqa: F401
    except ImportError as e:
        print(f"skipped: the keymesh extension is not built (PYTHONPATH=<build>/python): {e}")
        sys.exit(77)
    import pytest

    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider"] + sys.argv[1:]))
