"""`keymesh labels` smoothed surfaces cross nowhere and hold no zero-area
triangle (docs/decisions/labels-smoothing-folds.md), by `keymesh check
--self-intersections` (exact predicates): the surface nets network of the
AAL atlas (Debian mricron-data; 116 labels, 3,429 crossing pairs before the
fold guard) and of a many-label noise volume. Every label's own surface, and
discrete MC, are checked by the gtests LabelsFolds.*. Skipped (77) without
the atlas and numpy."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, run, tempdir, write_label_nrrd  # noqa: E402

AAL = "/usr/share/mricron/templates/aal.nii.gz"
D = tempdir()


def crosses_nowhere(volume, name, *args):
    def test():
        out = os.path.join(D, f"{name}.vtp")
        run("labels", volume, "-o", out, "-q", *args)
        run("check", out, "--self-intersections", "--report", out + ".json", "-q")
        r = report(out + ".json")
        assert r["self_intersections"] == 0 and r["zero_area_triangles"] == 0, (
            r["self_intersections"], r["zero_area_triangles"], r["self_intersecting_pairs"][:4])
    return test


skipped = []
try:
    import numpy as np
except ImportError:
    np = None
    skipped.append("numpy missing")
if np is not None:
    # 12 labels, each voxel the label of its largest box-filtered noise
    # field: blobs a few voxels wide, three or more labels meeting all over.
    f = np.random.default_rng(2).random((12, 32, 30, 28), dtype=np.float32)
    for _ in range(2):
        for axis in (1, 2, 3):
            f = (np.roll(f, 1, axis) + f + np.roll(f, -1, axis)) / 3
    noise = write_label_nrrd(os.path.join(D, "argmax12.nrrd"), np.argmax(f, axis=0) + 1)
    check("12-label noise, surface nets network: no crossing pair, no zero-area triangle",
          crosses_nowhere(noise, "noise"))
    check("12-label noise, --smooth 40: no crossing pair, no zero-area triangle",
          crosses_nowhere(noise, "noise40", "--smooth", 40))
if os.path.exists(AAL):
    check("AAL atlas, surface nets network: no crossing pair, no zero-area triangle", crosses_nowhere(AAL, "aal"))
else:
    skipped.append(f"{AAL} not found (apt-get install mricron-data)")
finish("; ".join(skipped) if skipped else None)
