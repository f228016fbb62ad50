"""ctest entry for the Python module: pytest -q over tests/python.

Exits 77 (ctest: skipped) when pytest or numpy is missing or when the
extension was not built into PYTHONPATH; otherwise pytest's exit status.
"""
import importlib.util
import sys

if __name__ == "__main__":
    for needed in ("pytest", "numpy"):
        if importlib.util.find_spec(needed) is None:
            print(f"skipped: {needed} is not installed for {sys.executable}")
            sys.exit(77)
    if importlib.util.find_spec("keymesh._keymesh") is None:
        print("skipped: the keymesh extension is not built (PYTHONPATH=<build>/python)")
        sys.exit(77)
    import pytest

    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider"] + sys.argv[1:]))
