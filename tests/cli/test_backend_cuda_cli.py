"""`--backend cuda` on every command with a GPU path (issue 35): contour of a
volume (plain, --curvature and --coarsen) and of a tet grid, tetrahedralize (5 and 24
tets), subdivide (triangles linear and Bezier, tets), dual, labels (surface
nets, smoothed with its fold guard and --smooth 0), pipeline --subdivide,
--coarsen and --dual.

Where the GPU cannot run them (a build without CUDA, as CI's, or no device,
as the development machine), each exits 1 with one line that says why and
names --backend cpu, and leaves no output. Where it can, each output equals
--backend cpu's byte for byte. Either way, what a GPU path lacks is refused
by name before the device is considered, and the commands without one
refuse --backend cuda by name.
"""
import filecmp
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import numpy as np  # noqa: E402
from kmtest import check, finish, run, tempdir, write_label_nrrd  # noqa: E402

D = tempdir()
VTI = os.path.join(D, "sphere.vti")
TETS = os.path.join(D, "tets.vtu")
SURFACE = os.path.join(D, "surface.ply")
run("generate", "sphere", "--size", 12, "-o", VTI, "-q")
run("tetrahedralize", VTI, "-o", TETS, "-q")
run("contour", VTI, "-o", SURFACE, "--iso", 4.5, "--normals", "average", "-q")
LABELS = write_label_nrrd(os.path.join(D, "labels.nrrd"),
                          np.fromfunction(lambda x, y, z: (x // 3 + y // 4 + z // 5) % 4, (13, 11, 9), dtype=int))

# (command, input, output extension, arguments)
GPU_COMMANDS = [
    ("contour", VTI, "ply", ["--iso", 4.5, "--normals", "average"]),
    ("contour", VTI, "ply", ["--iso", 4.5, "--iso", 2.5, "--normals", "average", "--coarsen"]),
    ("contour", VTI, "vtp", ["--iso", 4.5, "--normals", "gradient", "--curvature"]),
    ("contour", VTI, "vtp", ["--iso", 4.5, "--curvature", "--coarsen"]),
    ("contour", TETS, "ply", ["--iso", 4.5, "--iso", 3.001, "--normals", "average"]),
    ("tetrahedralize", VTI, "vtu", ["--scheme", 5]),
    ("tetrahedralize", VTI, "vtu", ["--scheme", 24]),
    ("subdivide", SURFACE, "ply", ["--levels", 2]),
    ("subdivide", SURFACE, "ply", ["--levels", 2, "--scheme", "bezier"]),
    ("subdivide", TETS, "vtu", ["--levels", 1]),
    ("pipeline", VTI, "ply", ["--iso", 4.5, "--subdivide", 1]),
    ("pipeline", TETS, "ply", ["--iso", 4.5]),
    ("pipeline", VTI, "ply", ["--iso", 4.5, "--coarsen", "--dual"]),
    ("dual", SURFACE, "ply", []),
    ("labels", LABELS, "vtp", ["--smooth", 0]),
    ("labels", LABELS, "vtp", []),  # --smooth 16 by default
    ("labels", LABELS, "vtp", ["--smooth", 5, "--relaxation", 0.9]),
]


def output(name, ext):
    return os.path.join(D, name + "." + ext)


def gpu_runs_or_says_why():
    refused = 0
    for i, (command, inp, ext, args) in enumerate(GPU_COMMANDS):
        cpu, gpu = output(f"cpu{i}", ext), output(f"gpu{i}", ext)
        run(command, inp, "-o", cpu, "-q", *args)
        p = run(command, inp, "-o", gpu, "-q", "--backend", "cuda", *args, expect=None)
        if p.returncode == 0:
            assert filecmp.cmp(cpu, gpu, shallow=False), f"{command} {args}: cuda differs from cpu"
            continue
        refused += 1
        assert p.returncode == 1, (command, args, p.returncode, p.stderr)
        assert p.stderr.count("\n") == 1, p.stderr
        assert "--backend cuda: " in p.stderr and "(use --backend cpu)" in p.stderr, p.stderr
        assert any(why in p.stderr for why in ("no usable CUDA device", "no CUDA device present",
                                               "built without the CUDA backend")), p.stderr
        assert not os.path.exists(gpu), gpu
    # The machine either runs them all or none.
    assert refused in (0, len(GPU_COMMANDS)), refused


def lacking_refused_by_name():
    cases = [
        (["contour", TETS, "--iso", 4.5, "--weld", "vertexweld"], "VERTEX-WELD"),
        (["contour", TETS, "--iso", 4.5, "--coarsen"], "coarsening"),
        (["tetrahedralize", VTI, "--scheme", 24, "--weld", "vertexweld"], "VERTEX-WELD"),
        (["subdivide", SURFACE, "--weld", "vertexweld"], "VERTEX-WELD"),
        (["labels", LABELS, "--smooth", 0, "--memory-limit", "1M"], "streaming (--memory-limit)"),
        (["quality", SURFACE], "quality"),
    ]
    for args, name in cases:
        out = output("refused", "vtu" if args[0] == "tetrahedralize" else "ply")
        p = run(*args[:2], "-o", out, *args[2:], "--backend", "cuda", expect=None) if args[0] != "quality" \
            else run(*args, "--backend", "cuda", expect=None)
        assert p.returncode == 1, (args, p.returncode, p.stderr)
        assert name in p.stderr and "is not available on the GPU yet (use --backend cpu)" in p.stderr, p.stderr
        assert p.stderr.count("\n") == 1, p.stderr
        assert not os.path.exists(out), out


def bad_input_as_on_the_cpu():
    plain = os.path.join(D, "plain.ply")  # no normals: Bezier refuses it
    THIN = write_label_nrrd(os.path.join(D, "thin.nrrd"), np.arange(20).reshape(5, 1, 4))  # one plane: no cells
    run("contour", VTI, "-o", plain, "--iso", 4.5, "-q")
    cases = [
        ["contour", TETS, "-o", output("x", "ply"), "--iso", 1, "--array", "nope"],
        ["contour", THIN, "-o", output("x", "ply"), "--iso", 5.5, "--coarsen"],
        ["labels", VTI, "-o", output("x", "vtp"), "--smooth", 0],
        ["subdivide", plain, "-o", output("x", "ply"), "--scheme", "bezier"],
    ]
    for args in cases:
        cpu = run(*args, expect=None)
        gpu = run(*args, "--backend", "cuda", expect=None)
        assert cpu.returncode == 1 and cpu.stderr.count("\n") == 1, (args, cpu.returncode, cpu.stderr)
        assert (gpu.returncode, gpu.stderr) == (cpu.returncode, cpu.stderr), (args, cpu.stderr, gpu.stderr)


check("--backend cuda: the GPU's output is the CPU's, or one line naming --backend cpu", gpu_runs_or_says_why)
check("--backend cuda: what a GPU path lacks is refused by name", lacking_refused_by_name)


def label_options_the_device_lacks():
    # Refused by name (the device path's own words), after the CPU's checks.
    cases = [
        (["--method", "discrete-mc"], "--method discrete-mc"),
        (["--per-label"], "--per-label"),
        (["--coarsen"], "--coarsen"),
    ]
    for args, name in cases:
        out = output("refused", "vtp")
        p = run("labels", LABELS, "-o", out, *args, "--backend", "cuda", expect=None)
        assert p.returncode == 1, (args, p.returncode, p.stderr)
        assert name in p.stderr and "(use --backend cpu)" in p.stderr, p.stderr
        assert p.stderr.count("\n") == 1, p.stderr
        assert not os.path.exists(out), out


check("--backend cuda: bad input gets the CPU's message", bad_input_as_on_the_cpu)
check("--backend cuda: what the label path lacks is refused by name", label_options_the_device_lacks)
finish()
