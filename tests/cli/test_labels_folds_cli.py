"""`keymesh labels` smoothed surfaces cross nowhere and hold no zero-area
triangle (docs/decisions/labels-smoothing-folds.md), by `keymesh check
--self-intersections` (exact predicates): the surface nets network of the
AAL atlas (Debian mricron-data; 116 labels, 3,429 crossing pairs before the
fold guard) and of a many-label noise volume. Every label's own surface, and
discrete MC, are checked by the gtests LabelsFolds.*. The report's
guard_shortened (moves the guard shortened or refused) on the noise volume:
> 0, the same at --threads 1 and 2 and in slabs, 0 with --smooth 0.
Skipped (77) without the atlas and numpy."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, junction_labels, report, run, tempdir, write_label_nrrd  # noqa: E402

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


def guard_shortened_reported(volume, dims):
    """The report's guard_shortened: > 0 where the guard acts, the same
    count at 1 and 2 threads and streamed in slabs, 0 unsmoothed."""
    def test():
        def shortened(name, *args):
            out = os.path.join(D, f"{name}.vtp")
            run("labels", volume, "-o", out, "-q", "--report", out + ".json", *args)
            r = report(out + ".json")
            assert "--memory-limit" not in args or r["stream"]["slabs"] > 1, r["stream"]
            return r["guard_shortened"]
        smoothed = shortened("guard_t1", "--threads", 1)
        assert smoothed > 0, smoothed
        assert shortened("guard_t2", "--threads", 2) == smoothed
        # A padded row: uint8 samples and 16-bit label indices with a border of one.
        row = dims[0] * dims[1] + 2 * (dims[0] + 2) * (dims[1] + 2)
        assert shortened("guard_slabs", "--memory-limit", 4 * row) == smoothed
        assert shortened("guard_off", "--smooth", 0) == 0
    return test


skipped = []
try:
    import numpy as np
except ImportError:
    np = None
    skipped.append("numpy missing")
if np is not None:
    NOISE_DIMS = (32, 30, 28)
    noise = write_label_nrrd(os.path.join(D, "argmax12.nrrd"), junction_labels(NOISE_DIMS, 12, 2))
    check("12-label noise, surface nets network: no crossing pair, no zero-area triangle",
          crosses_nowhere(noise, "noise"))
    check("12-label noise, --smooth 40: no crossing pair, no zero-area triangle",
          crosses_nowhere(noise, "noise40", "--smooth", 40))
    check("12-label noise: report guard_shortened > 0 smoothed, the same at --threads 1 and 2 and streamed; "
          "0 with --smooth 0", guard_shortened_reported(noise, NOISE_DIMS))
if os.path.exists(AAL):
    check("AAL atlas, surface nets network: no crossing pair, no zero-area triangle", crosses_nowhere(AAL, "aal"))
else:
    skipped.append(f"{AAL} not found (apt-get install mricron-data)")
finish("; ".join(skipped) if skipped else None)
