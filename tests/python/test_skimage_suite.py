"""scikit-image's own marching cubes tests, run against keymesh (issue 33).

The installed test file (python3-skimage: skimage/measure/tests/
test_marching_cubes.py) is run by pytest in a fresh interpreter whose
skimage.measure.marching_cubes is keymesh.marching_cubes: the file imports
the function from there, so every one of its tests calls keymesh. Nothing of
it is copied here."""
import os
import subprocess
import sys

import pytest

RUNNER = """
import sys, pytest, keymesh, skimage.measure
skimage.measure.marching_cubes = keymesh.marching_cubes
sys.exit(pytest.main([sys.argv[1], "-q", "-p", "no:cacheprovider", "-W", "ignore::DeprecationWarning"]))
"""


def test_scikit_images_own_test_file_passes_against_keymesh():
    measure = pytest.importorskip("skimage.measure")
    path = os.path.join(os.path.dirname(measure.__file__), "tests", "test_marching_cubes.py")
    if not os.path.exists(path):
        pytest.skip("python3-skimage ships no tests here")
    p = subprocess.run([sys.executable, "-c", RUNNER, path], capture_output=True, text=True, timeout=600,
                       env=dict(os.environ), stdin=subprocess.DEVNULL)
    tail = p.stdout.strip().splitlines()[-1] if p.stdout.strip() else p.stderr
    assert p.returncode == 0, p.stdout[-4000:] + p.stderr[-2000:]
    assert " passed" in tail and "failed" not in tail, tail
