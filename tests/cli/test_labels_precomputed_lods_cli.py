"""`keymesh labels --format precomputed` levels of detail cross nowhere
(issue 37; docs/decisions/labels-lod-fold-guard.md): each segment's decoded
fragments of one level, every chunk's joined at their exact quantized
positions (so pairs across neighbouring chunks count), hold no crossing
pair and no zero-area triangle at ANY level, judged by `keymesh check
--self-intersections` (exact predicates). Volumes: blobs of six labels
meeting along triple lines and at junction points, and white noise of four
labels (thin, self-touching regions across every chunk edge line); 3 levels.
Before the coarsening's fold guard these had tens to hundreds of pairs at
lods 1-2. Chunk faces still agree: tests/cli/test_labels_precomputed_cli.py."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (check, finish, junction_labels, precomputed_level_crossings, precomputed_reader, run,  # noqa: E402
                    tempdir, write_label_nrrd)

np, ngp = precomputed_reader()
D = tempdir()


def noise(shape, seed):
    return np.random.default_rng(seed).integers(1, 5, shape).astype(np.uint8)


def crosses_at_no_level(volume, name, chunk):
    def test():
        path = write_label_nrrd(os.path.join(D, name + ".nrrd"), volume)
        out = os.path.join(D, name)
        run("labels", path, "-o", out, "--format", "precomputed", "--lods", "3", "--chunk-shape", chunk, chunk, chunk)
        segments = sorted(int(v) for v in np.unique(volume) if v)
        found = precomputed_level_crossings(ngp, out, segments, D)
        assert {lod for _, lod in found} == {0, 1, 2}, sorted(found)  # every level is checked
        bad = {k: v[:2] for k, v in found.items() if v[0] or v[1]}
        assert not bad, f"(segment, lod): (crossing pairs, zero-area triangles) {bad}"
    return test


check("six labels, triple lines and junctions, 3 levels: no crossing pair at any level",
      crosses_at_no_level(junction_labels((36, 32, 30), 6, 1), "junctions", 16))
check("white noise of four labels, 3 levels: no crossing pair at any level",
      crosses_at_no_level(noise((24, 22, 20), 1), "noise", 8))
finish()
