"""What `import keymesh` loads: GDCM only once a DICOM series is read (its
module, libkeymesh_gdcm.so, is found beside the extension)."""
import os
import subprocess
import sys

import numpy as np
import pytest

import keymesh

TESTS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Run in a fresh interpreter: this session may have read DICOM already.
PROBE = r"""
import sys
import numpy as np
import keymesh

def gdcm_mapped():
    with open("/proc/self/maps") as f:
        return sorted({line.split()[-1].rsplit("/", 1)[-1] for line in f if "gdcm" in line.lower()})

print("after import:", gdcm_mapped())
vol = keymesh.read(sys.argv[1])
print("after read:", gdcm_mapped(), vol.array.shape)
"""


def test_gdcm_is_loaded_by_the_first_dicom_read(tmp_path):
    pytest.importorskip("pydicom")
    sys.path.insert(0, TESTS)
    from dicom_series import write_dicom_series
    write_dicom_series(str(tmp_path / "series"), np.zeros((3, 4, 5), np.int16), slope=1.0, intercept=0.0)
    p = subprocess.run([sys.executable, "-c", PROBE, str(tmp_path / "series")], capture_output=True, text=True,
                       timeout=300, env=dict(os.environ))
    assert p.returncode == 0, p.stderr
    after_import, after_read = p.stdout.splitlines()
    assert after_import == "after import: []"
    assert "libkeymesh_gdcm.so" in after_read and "libgdcmMSFF" in after_read
    assert after_read.endswith("(5, 4, 3)")

