#!/usr/bin/env python3
"""`make bench`: the paper's Tables 1-6 on this machine, keymesh beside its
peers in one run: the Spherical Distance field (128^3, 256^3, 512^3) and the
real datasets of bench/datasets.py (MRI head 128^3 and 256^3, the 432^3
supernova stand-in), built at bench time from Debian packages.

Writes bench/results/latest.jsonl (one JSON object per case; every row has
`dataset` and the load average when it was measured), prints the tables of
medians with ratios, renders the pictures (docs/results/*.png) and runs
bench/report.py, which writes docs/RESULTS.md. `make bench QUICK=1` runs
128^3 and 256^3 only, with 3 repetitions.

Every process (keymesh and the VTK peer) runs with glibc.malloc.hugetlb=1 in
GLIBC_TUNABLES, the setting keymesh gives itself, so that neither side is
measured paying 4 KiB page faults that the other does not.
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time


HERE = os.path.dirname(os.path.abspath(__file__))
SYSTEM_PYTHON = "/usr/bin/python3"


def env_hugepages(huge_pages=True):
    env = dict(os.environ)
    t = env.get("GLIBC_TUNABLES", "")
    if huge_pages and "glibc.malloc.hugetlb" not in t:
        env["GLIBC_TUNABLES"] = (t + ":" if t else "") + "glibc.malloc.hugetlb=1"
    if not huge_pages:
        env["GLIBC_TUNABLES"] = ":".join(x for x in t.split(":") if x and "glibc.malloc.hugetlb" not in x)
    return env


def run_json(cmd, extra_env=None, huge_pages=True):
    env = env_hugepages(huge_pages)
    env.update(extra_env or {})
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.stderr.write(p.stderr)
        raise SystemExit(f"bench: {' '.join(cmd)} failed")
    rows = [json.loads(line) for line in p.stdout.splitlines() if line.startswith("{")]
    for r in rows:
        r["loadavg"] = round(os.getloadavg()[0], 2)
    return rows


class Progress:
    """Step counter with elapsed time, so a long run shows where it is."""

    def __init__(self):
        self.t0 = time.time()
        self.step = 0

    def __call__(self, text):
        self.step += 1
        el = time.time() - self.t0
        el = int(el)
        print(f"  [{self.step:3d} {el // 60:2d}:{el % 60:02d} load {os.getloadavg()[0]:4.1f}] {text}", flush=True)


progress = Progress()


def skipped(tool, reason, **kw):
    print(f"  {tool} skipped: {reason}", flush=True)
    return dict(bench="skipped", tool=tool, reason=reason, **kw)


def peer(script, args, tool, **kw):
    """The rows of a peer script of bench/ run with Debian's python3 (VTK
    comes from python3-vtk9), or one row saying why `tool` was skipped."""
    try:
        return run_json([SYSTEM_PYTHON, os.path.join(HERE, script), *args])
    except SystemExit as e:
        return [skipped(tool, str(e), **kw)]


def keymesh_row(cmd):
    """The row of one run of a keymesh harness (contour_bench, ops_bench)."""
    r = run_json(cmd)[0]
    r["tool"] = "keymesh"
    return r


def volume_vti(keymesh, work, n, d=None):
    """The volume's .vti: a dataset's of datasets.py, else the n^3 sphere, generated once into work."""
    vti = d["vti"] if d else os.path.join(work, f"sphere{n}.vti")
    if not os.path.exists(vti):
        subprocess.run([keymesh, "generate", "sphere", "--size", str(n), "-o", vti, "-q"], check=True)
    return vti


def machine():
    cpu = "unknown"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    cxx = subprocess.run(["c++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    return {"cpu": cpu, "cores": os.cpu_count(), "memory_gib": round(mem, 1), "compiler": cxx,
            "date": time.strftime("%Y-%m-%d"), "kernel": platform.release()}


def cli_cold(keymesh, size, iso, threads, reps, workdir):
    """`keymesh contour` as a user runs it: a fresh process per run; seconds.contour from --report."""
    vti = volume_vti(keymesh, workdir, size)
    times, rss = [], 0
    for _ in range(reps):
        rep = os.path.join(workdir, "r.json")
        subprocess.run([keymesh, "contour", vti, "-o", os.path.join(workdir, "o.vtp"), "--iso", str(iso),
                        "--threads", str(threads), "--no-scalars", "--report", rep, "--quiet"], check=True)
        r = json.load(open(rep))
        times.append(r["seconds"]["contour"])
        rss = max(rss, r["peak_rss_mib"])
        points, cells = r["points"], r["cells"]
    return {"bench": "contour", "tool": "keymesh-cli", "size": size, "iso": iso, "threads": threads,
            "weld": "keyreduce", "normals": "none", "points": points, "cells": cells,
            "median": statistics.median(times), "min": min(times), "max": max(times), "reps": reps,
            "peak_rss_mib": rss, "loadavg": round(os.getloadavg()[0], 2)}


def vtk_cold(size, iso, threads, reps, workdir):
    """vtkFlyingEdges3D as a one-shot program: a fresh process reads the .vti and contours once, like the CLI."""
    vti = os.path.join(workdir, f"sphere{size}.vti")
    times, rss = [], 0
    for _ in range(reps):
        r = run_json([SYSTEM_PYTHON, os.path.join(HERE, "peers", "vtk_contour.py"), "--size", str(size), "--file", vti,
                      "--iso", str(iso), "--threads", str(threads), "--reps", "1", "--filters", "vtkFlyingEdges3D"])[0]
        times.append(r["median"])
        rss = max(rss, r["peak_rss_mib"])
    r.update({"tool": "vtkFlyingEdges3D-cold", "median": statistics.median(times), "min": min(times),
              "max": max(times), "reps": reps, "peak_rss_mib": rss})
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--reps", type=int, default=0)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "latest.jsonl"))
    ap.add_argument("--summarize", action="store_true", help="only re-print the tables of --out")
    ap.add_argument("--no-report", action="store_true", help="do not run bench/report.py at the end")
    a = ap.parse_args()
    sizes = [128, 256] if a.quick else [128, 256, 512]
    names = ["head128", "head256"] if a.quick else ["head128", "head256", "big432"]
    if a.summarize:
        rows = [json.loads(line) for line in open(a.out)]
        sphere = [r for r in rows if r.get("dataset", "sphere") == "sphere"]
        sizes = sorted({r["size"] for r in sphere if "size" in r})
        threads_all = max(r.get("threads", 1) for r in sphere)
        write_summary(sphere, rows[0]["machine"], sizes, threads_all, a)
        return
    reps = a.reps or (3 if a.quick else 7)
    peer_reps = a.reps or (3 if a.quick else 5)  # the slow peers (single-threaded, seconds per run)
    threads_all = os.cpu_count() or 1
    bench = os.path.join(a.build, "contour_bench")
    keymesh = os.path.join(a.build, "keymesh")
    ops = os.path.join(a.build, "ops_bench")
    thrust = os.path.join(a.build, "thrust_weld")
    rows = []
    info = machine()
    t_start, load_start = time.time(), os.getloadavg()
    print(f"keymesh bench on {info['cpu']}, {info['cores']} cores, {info['memory_gib']} GiB, {info['date']}; "
          f"load average {load_start[0]:.1f}")
    print(f"sphere {sizes}, datasets {names}; {reps} repetitions per case ({peer_reps} for the slow peers); "
          f"expect about {EXPECTED_MINUTES['quick' if a.quick else 'full']} minutes on a 2-core VM "
          f"(measured under load 4-5)", flush=True)
    with tempfile.TemporaryDirectory(prefix="keymesh-bench-") as work:
        for n in sizes:
            iso = n / 2 - 1 + 0.001
            part = []
            part += contour_rows(bench, n, iso, threads_all, reps, None, f"{n}^3 sphere")
            if n == sizes[-1] and threads_all > 1:
                # libgomp's threads spin at barriers (OMP_WAIT_POLICY unset):
                # on a loaded VM a spinning thread holds a core the other needs.
                # The same case with passive waiting, to show what that costs.
                progress(f"{n}^3 sphere keymesh keyreduce threads={threads_all} OMP_WAIT_POLICY=passive")
                r = run_json([bench, "--size", str(n), "--threads", str(threads_all), "--reps", str(reps),
                              "--iso", str(iso)], {"OMP_WAIT_POLICY": "passive"})[0]
                r.update(tool="keymesh", weld="keyreduce-passive")
                part.append(r)
            progress(f"{n}^3 keymesh CLI (fresh process per run)")
            part.append(cli_cold(keymesh, n, iso, threads_all, reps, work))
            progress(f"{n}^3 VTK")
            try:
                part += run_json([SYSTEM_PYTHON, os.path.join(HERE, "peers", "vtk_contour.py"), "--size", str(n),
                                  "--iso", str(iso), "--threads", str(threads_all), "--reps", str(reps),
                                  "--filters", VTK_CONTOUR_PEERS])
                part.append(vtk_cold(n, iso, threads_all, reps, work))
            except SystemExit as e:
                part.append(skipped("vtkFlyingEdges3D", str(e), size=n))
            part += peer_rows(thrust, n, iso, None, threads_all, reps, peer_reps)
            if n <= (128 if a.quick else 256):
                part += tet_rows(bench, keymesh, n, iso, threads_all, reps, work)
            part += ops_rows(ops, keymesh, n, iso, threads_all, reps, work, quick=a.quick)
            for r in part:
                r.setdefault("dataset", "sphere")
            rows += part
        for name in names:
            progress(f"dataset {name}: building from Debian's files")
            d = json.loads(subprocess.run([SYSTEM_PYTHON, os.path.join(HERE, "datasets.py"), name, keymesh, work],
                                          check=True, capture_output=True, text=True).stdout)
            n, iso = d["size"], d["iso"]
            part = [{"bench": "dataset", **{k: v for k, v in d.items() if k not in ("nrrd", "vti")}}]
            # QUICK: the datasets at all threads only, 256^3 without tets and the other operations
            part += contour_rows(bench, n, iso, threads_all, reps, d["nrrd"], name, all_only=a.quick)
            progress(f"{name} VTK")
            part += peer("peers/vtk_contour.py", ["--size", str(n), "--file", d["vti"], "--iso", str(iso),
                                                  "--threads", str(threads_all), "--reps",
                                                  str(peer_reps if n > 256 else reps), "--filters", VTK_CONTOUR_PEERS],
                         "vtkFlyingEdges3D", size=n)
            part += peer_rows(thrust, n, iso, d["nrrd"], threads_all, reps, peer_reps)
            if n <= 128 or (n <= 256 and not a.quick):
                part += tet_rows(bench, keymesh, n, iso, threads_all, reps, work, d, all_only=a.quick)
            if n <= 128 or not a.quick:
                part += ops_rows(ops, keymesh, n, iso, threads_all, reps, work, d, quick=a.quick)
            for r in part:
                r["dataset"] = name
            rows += part
        progress("label maps: the AAL atlas, keymesh.contour_labels vs vtkDiscreteFlyingEdges3D (labels_bench.py)")
        try:
            rows += run_json([SYSTEM_PYTHON, os.path.join(HERE, "labels_bench.py"), "--json", "--threads",
                              str(threads_all), "--repeat", str(peer_reps)], {"PYTHONPATH": os.path.join(a.build, "python")})
        except SystemExit as e:
            rows.append(skipped("labels_bench.py", str(e)))
        progress("multi-resolution label meshes: the AAL atlas to 3 levels of detail vs VTK (lods_bench.py)")
        try:
            rows += run_json([SYSTEM_PYTHON, os.path.join(HERE, "lods_bench.py"), "--json", "--keymesh",
                              os.path.join(a.build, "keymesh"), "--threads", str(threads_all), "--repeat", str(peer_reps)])
        except SystemExit as e:
            rows.append(skipped("lods_bench.py", str(e)))
        rows += dense_rows(bench, a.build, threads_all, peer_reps, work, a.quick)
        progress("pictures (Figures 8-10), rendered off-screen with VTK")
        rows += figures(keymesh, work, "head128" if a.quick else names[-1], a.quick)
    seconds = time.time() - t_start
    rows.append({"bench": "run", "quick": a.quick, "rss_clean": True, "seconds": round(seconds, 1), "reps": reps, "peer_reps": peer_reps,
                 "loadavg_start": [round(x, 2) for x in load_start],
                 "loadavg_end": [round(x, 2) for x in os.getloadavg()], "command":
                 "make bench QUICK=1" if a.quick else "make bench"})
    for r in rows:
        r["machine"] = info
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    # every run's duration, kept across runs (report.py lists today's)
    with open(os.path.join(os.path.dirname(a.out), "durations.jsonl"), "a") as f:
        f.write(json.dumps({k: rows[-1][k] for k in ("command", "seconds", "loadavg_start", "loadavg_end")} |
                           {"date": info["date"], "time": time.strftime("%H:%M")}) + "\n")
    sphere = [r for r in rows if r.get("dataset") == "sphere"]
    write_summary(sphere, info, sizes, threads_all, a)
    print(f"bench: {seconds / 60:.1f} minutes; load average {load_start[0]:.1f} at the start, "
          f"{os.getloadavg()[0]:.1f} at the end")
    if not a.no_report:
        subprocess.run([SYSTEM_PYTHON, os.path.join(HERE, "report.py"), "--results", a.out], check=True)


# VTK's contour filters, and vtkCleanPolyData welding the contour's soup (VTK's VERTEX-WELD)
VTK_CONTOUR_PEERS = "vtkFlyingEdges3D,vtkMarchingCubes,vtkCleanPolyData"

# Measured on the development VM (2 cores) on 2026-11-23 under the load of
# other builds (load average 4-5): full 17.5 min, QUICK 2.1 min, plus the
# build; printed at the start so that a user knows what to expect.
EXPECTED_MINUTES = {"quick": 2, "full": 18}


def dense_rows(bench, build, threads, reps, work, quick):
    """Issue 17's real and dense volumes (bench/dense.py): keymesh.contour and
    vtkFlyingEdges3D in one Python process on the same arrays, with huge pages
    (glibc.malloc.hugetlb=1) and with the default malloc of a Python process;
    then the C++ harness (contour_bench, positions and triangles only, as
    dense.py runs both tools) on the same volumes written as .nrrd, with huge
    pages and without (KEYMESH_HUGE_PAGES=0: no re-exec), with
    vtkFlyingEdges3D in the harness's own process on the same samples
    (`--peer fe3d`, each tool's calls in two blocks; `fe3d_median` is its median).
    A harness built without VTK's C++ package (libvtk9-dev) refuses the
    peer; its rows then carry the FE3D median of dense.py's run with the
    same setting instead (`fe3d_same_process` false)."""
    # bet and inia19: volumes nothing here was tuned on (issue 17: "other real volumes").
    cases = "brain,brain8,head256" if quick else "brain,brain8,noise,head256,sphere512,bet,inia19"
    dense = os.path.join(HERE, "dense.py")
    env = {"PYTHONPATH": os.path.join(build, "python")}
    rows = []
    for huge in (True, False):
        progress(f"dense volumes {cases}: keymesh.contour vs vtkFlyingEdges3D, huge pages {huge}")
        try:
            rows += run_json([SYSTEM_PYTHON, dense, "--threads", str(threads), "--reps", str(reps), "--cases", cases,
                              "--single-isos"] + (["--dump", work] if huge else []), env, huge_pages=huge)
        except SystemExit as e:
            rows.append(skipped("dense.py", str(e)))
            return rows
    peer = ["--peer", "fe3d"] if harness_has_peer(bench) else []
    for r in [r for r in rows if r.get("dump")]:
        for huge in (True, False):
            progress(f"dense {r['case']}: contour_bench (C++ harness){' and FE3D' if peer else ''}, huge pages {huge}")
            c = run_json([bench, "--file", r["dump"], "--iso", ",".join(str(v) for v in r["isovalues"]),
                          "--threads", str(threads), "--reps", str(reps)] + peer,
                         None if huge else {"KEYMESH_HUGE_PAGES": "0"}, huge_pages=huge)[0]
            if "peer_median" in c:
                fe3d = c["peer_median"]
            else:
                fe = next((f for f in rows if f.get("case") == r["case"] and f.get("tool") == "vtkFlyingEdges3D"
                           and f.get("huge_pages") == huge), None)
                fe3d = fe["median"] if fe else None
            c.update(bench="dense", case=r["case"], tool="contour_bench", huge_pages=huge, fe3d_median=fe3d,
                     fe3d_same_process="peer_median" in c)
            rows.append(c)
    return rows


def harness_has_peer(bench):
    """Whether contour_bench was built with VTK's C++ package: a build
    without it refuses `--peer fe3d` by name (exit 2) before reading input."""
    p = subprocess.run([bench, "--peer", "fe3d", "--file", "/nonexistent", "--iso", "0", "--reps", "1"],
                       capture_output=True, text=True)
    return "built without VTK" not in p.stderr


def thread_counts(threads_all, all_only=False):
    return [threads_all] if all_only else sorted({1, threads_all})


def contour_rows(bench, n, iso, threads_all, reps, file, label, all_only=False):
    """Table 2's structured rows: VERTEX-WELD, KEY-REDUCE (sort and dense
    plans, no merge) and KEY-REDUCE averaging, at 1 thread and all threads."""
    rows = []
    for threads in thread_counts(threads_all, all_only):
        for weld, normals in (("vertexweld", "none"), ("keyreduce-sort", "none"),
                              ("keyreduce", "none"), ("keyreduce", "average")):
            progress(f"{label} keymesh {weld} normals={normals} threads={threads}")
            cmd = [bench, "--size", str(n), "--threads", str(threads), "--reps", str(reps), "--weld", weld,
                   "--normals", normals, "--iso", str(iso)]
            rows.append(keymesh_row(cmd + (["--file", file] if file else [])))
    return rows


def peer_rows(thrust, n, iso, file, threads_all, reps, peer_reps):
    """scikit-image marching_cubes, OpenVDB volumeToMesh and Bell's Thrust
    VERTEX-WELD (OpenMP backend) on the same volume; each skipped with its
    reason when it cannot run here."""
    rows = []
    src = ["--file", file] if file else []
    for tool in ("skimage", "openvdb"):
        progress(f"{n}^3 {tool}")
        try:
            rows += run_json([SYSTEM_PYTHON, os.path.join(HERE, "peers", "py_contour.py"), "--tool", tool,
                              "--size", str(n), "--iso", str(iso), "--reps", str(peer_reps)] + src)
        except SystemExit as e:
            rows.append(skipped(tool, f"{e} (python3-skimage / python3-openvdb installed?)", size=n))
    progress(f"{n}^3 Thrust VERTEX-WELD (OpenMP backend), threads={threads_all}")
    if os.path.exists(thrust):
        try:
            rows += run_json([thrust, "--size", str(n), "--iso", str(iso), "--threads", str(threads_all),
                              "--reps", str(reps)] + src)
        except SystemExit as e:
            rows.append(skipped("thrust-vertexweld", str(e), size=n))
    else:
        rows.append(skipped("thrust-vertexweld", f"{thrust} was not built: no Thrust headers compile with the "
                            "OpenMP backend (install libthrust-dev)", size=n))
    return rows


def figures(keymesh, work, big, quick):
    """The paper's Figures 8-10, rendered off-screen with VTK into docs/results."""
    out = os.path.join(os.path.dirname(HERE), "docs", "results")
    try:
        return json.loads(subprocess.run([SYSTEM_PYTHON, os.path.join(HERE, "figures.py"), "--keymesh", keymesh,
                                          "--work", work, "--big", big, "--out", out],
                                         capture_output=False, stdout=subprocess.PIPE, text=True,
                                         check=True).stdout.strip().splitlines()[-1])
    except (subprocess.CalledProcessError, ValueError, IndexError) as e:
        return [skipped("figures", f"bench/figures.py failed: {e}")]


def write_summary(rows, info, sizes, threads_all, a):
    text = summarize(rows, sizes, threads_all)
    md = os.path.splitext(a.out)[0] + ".md"
    with open(md, "w") as f:
        f.write(f"# keymesh bench, {info['date']}\n\n{info['cpu']}, {info['cores']} cores, {info['memory_gib']} GiB, "
                f"{info['compiler']}, Linux {info['kernel']}\n\nCommand: `make bench{' QUICK=1' if a.quick else ''}`"
                f"\n\n```\n{text}\n```\n")
    print(f"\nresults: {a.out} and {md}")


def tet_rows(bench, keymesh, n, iso, threads_all, reps, work, d=None, all_only=False):
    """Marching tetrahedra on the scheme-5 grid of the field (Table 2's
    unstructured rows): keymesh in-process, the CLI's tetrahedralize, and
    vtkContour3DLinearGrid on keymesh's .vtu. d: a dataset of datasets.py."""
    rows = []
    label = d["dataset"] if d else f"{n}^3"
    for threads in thread_counts(threads_all, all_only):
        for weld in ("vertexweld", "keyreduce"):
            progress(f"{label} tets keymesh {weld} threads={threads}")
            rows.append(keymesh_row([bench, "--size", str(n), "--threads", str(threads), "--reps", str(reps),
                                     "--grid", "tet5", "--weld", weld, "--iso", str(iso)] +
                                    (["--file", d["nrrd"]] if d else [])))
    vti = volume_vti(keymesh, work, n, d)
    vtu = os.path.join(work, f"tets{n}.vtu")
    rep = os.path.join(work, "tet.json")
    progress(f"{label} keymesh tetrahedralize (CLI)")
    subprocess.run([keymesh, "tetrahedralize", vti, "-o", vtu, "-q", "--report", rep], check=True,
                   env=env_hugepages())
    tr = json.load(open(rep))
    rows.append({"bench": "tetrahedralize", "tool": "keymesh-cli", "grid": "tet5", "size": n,
                 "threads": tr["threads"], "median": tr["seconds"]["tetrahedralize"], "cells": tr["cells"],
                 "peak_rss_mib": tr["peak_rss_mib"]})
    progress(f"{label} tets VTK")
    rows += peer("peers/vtk_tet_contour.py", ["--vtu", vtu, "--size", str(n), "--iso", str(iso), "--threads",
                                              str(threads_all), "--reps", str(reps)],
                 "vtkContour3DLinearGrid", size=n, grid="tet5")
    os.remove(vtu)
    return rows


def ops_rows(ops, keymesh, n, iso, threads_all, reps, work, d=None, quick=False):
    """The paper's Tables 3 and 4: triangle subdivision of the sphere contour
    (KEY-REDUCE, VERTEX-WELD, vtkLinearSubdivisionFilter) and the face-centred
    tetrahedralization (KEY-REDUCE, VERTEX-WELD; up to 128^3, 49 M tets)."""
    rows = []
    label = d["dataset"] if d else f"{n}^3"
    src = ["--iso", str(iso)] + (["--file", d["nrrd"]] if d else [])
    # QUICK: datasets at all threads only; tet24 (data-independent, ~10 s a run
    # at 128^3) once per weld at all threads on the sphere only
    all_only = quick and d is not None
    for threads in thread_counts(threads_all, all_only):
        for weld in ("vertexweld", "keyreduce"):
            progress(f"{label} subdivide {weld} threads={threads}")
            rows.append(keymesh_row([ops, "--op", "subdivide", "--size", str(n), "--threads", str(threads),
                                     "--reps", str(reps), "--weld", weld] + src))
            if n <= 128 and (not quick or (d is None and threads == threads_all)):
                progress(f"{label} tet24 {weld} threads={threads}")
                rows.append(keymesh_row([ops, "--op", "tet24", "--size", str(n), "--threads", str(threads), "--reps",
                                         str(1 if quick else min(reps, 3)), "--weld", weld] + src))
    for threads in thread_counts(threads_all, all_only):
        for op in ("contour", "coarsen", "dual"):
            progress(f"{label} {op} threads={threads}")
            rows.append(keymesh_row([ops, "--op", op, "--size", str(n), "--threads", str(threads), "--reps",
                                     str(reps)] + src))
    vti = volume_vti(keymesh, work, n, d)
    vtp = os.path.join(work, f"contour{n}.vtp")
    if quick and d is not None:
        return rows  # QUICK: the VTK surface peers on the sphere only
    subprocess.run([keymesh, "contour", vti, "-o", vtp, "--iso", str(iso), "--normals", "average", "-q"], check=True)
    progress(f"{label} subdivide VTK")
    rows += peer("peers/vtk_subdivide.py", ["--mesh", vtp, "--size", str(n), "--reps", str(reps)],
                 "vtkLinearSubdivisionFilter", size=n)
    progress(f"{label} decimation VTK")
    rows += peer("peers/vtk_decimate.py", ["--mesh", vtp, "--size", str(n), "--reps", str(reps)],
                 "vtkBinnedDecimation", size=n)
    os.remove(vtp)
    return rows


def find(rows, **kw):
    for r in rows:
        if all(r.get(k) == v for k, v in kw.items()):
            return r
    return None


def summarize(rows, sizes, threads):
    """Prints the tables and returns them as text (for bench/results/latest.md)."""
    lines = []

    def out(text=""):
        print(text)
        lines.append(text)

    out("\nMarching cubes + weld, Spherical Distance field at iso N/2 - 1 + 0.001 (the paper's Table 1 surfaces)")

    def medians(label, sizes_, **kw):
        """One line of a table: the case's median (min-max) at each size, blank where it did not run."""
        cells = []
        for n in sizes_:
            r = find(rows, size=n, **kw)
            cells.append(f"{r['median'] * 1e3:8.1f} ({r.get('min', r['median']) * 1e3:.0f}-"
                         f"{r.get('max', r['median']) * 1e3:.0f})" if r else "")
        out(f"{label:44s} " + " ".join(f"{c:>19s}" for c in cells))

    def line(label, **kw):
        medians(label, sizes, **kw)

    out("\nWarm: medians of repetitions in one process (ms; min-max)")
    out(f"{'case':44s} " + " ".join(f"{n:>16d}^3" for n in sizes))
    for t in sorted({1, threads}):
        line(f"keymesh VERTEX-WELD, {t} thr", tool="keymesh", grid="voxel", weld="vertexweld", threads=t)
        line(f"keymesh KEY-REDUCE sort plan, {t} thr", tool="keymesh", grid="voxel", weld="keyreduce-sort", threads=t)
        line(f"keymesh KEY-REDUCE dense plan, no merge, {t} thr", tool="keymesh", grid="voxel", weld="keyreduce",
             normals="none", threads=t)
        line(f"keymesh KEY-REDUCE averaging, {t} thr", tool="keymesh", grid="voxel", weld="keyreduce",
             normals="average", threads=t)
    line(f"vtkFlyingEdges3D, {threads} thr", tool="vtkFlyingEdges3D")
    line("vtkMarchingCubes, 1 thr", tool="vtkMarchingCubes")

    out("\nCold: the first run in a fresh process, touching fresh memory (ms)")
    out(f"{'case':44s} " + " ".join(f"{n:>16d}^3" for n in sizes))

    def cold(label, key, **kw):
        cells = []
        for n in sizes:
            r = find(rows, size=n, **kw)
            cells.append(f"{r[key] * 1e3:8.1f}" if r else "")
        out(f"{label:44s} " + " ".join(f"{c:>19s}" for c in cells))

    cold(f"keymesh KEY-REDUCE, first repetition, {threads} thr", "first", tool="keymesh", grid="voxel",
         weld="keyreduce", normals="none", threads=threads)
    cold(f"keymesh CLI seconds.contour (median), {threads} thr", "median", tool="keymesh-cli")
    cold(f"vtkFlyingEdges3D, first repetition, {threads} thr", "first", tool="vtkFlyingEdges3D")
    cold(f"vtkFlyingEdges3D one-shot (median), {threads} thr", "median", tool="vtkFlyingEdges3D-cold")

    out("\nRatios (higher is better for keymesh)")
    for n in sizes:
        kr = find(rows, size=n, tool="keymesh", grid="voxel", weld="keyreduce", normals="none", threads=threads)
        av = find(rows, size=n, tool="keymesh", grid="voxel", weld="keyreduce", normals="average", threads=threads)
        vw = find(rows, size=n, tool="keymesh", grid="voxel", weld="vertexweld", threads=threads)
        cli = find(rows, size=n, tool="keymesh-cli")
        fe = find(rows, size=n, tool="vtkFlyingEdges3D")
        parts = []
        if kr and fe:
            parts.append(f"vtkFlyingEdges3D / keymesh, warm medians {fe['median'] / kr['median']:.2f}x")
            parts.append(f"cold first runs {fe['first'] / kr['first']:.2f}x")
        fe_cold = find(rows, size=n, tool="vtkFlyingEdges3D-cold")
        if cli and fe_cold:
            parts.append(f"one-shot: VTK / keymesh CLI seconds.contour {fe_cold['median'] / cli['median']:.2f}x")
        if kr and vw:
            parts.append(f"VERTEX-WELD / KEY-REDUCE {vw['median'] / kr['median']:.2f}x")
        if kr and av:
            parts.append(f"averaging overhead {100 * (av['median'] / kr['median'] - 1):+.0f}% (medians), "
                         f"{100 * (av['min'] / kr['min'] - 1):+.0f}% (minima)")
        out(f"  {n}^3, {threads} threads: " + "; ".join(parts))
    tet_sizes = [n for n in sizes if find(rows, size=n, grid="tet5")]
    if tet_sizes:
        out("\nMarching tetrahedra on the scheme-5 grid (5 (N-1)^3 tets), warm medians (ms; min-max)")
        out(f"{'case':44s} " + " ".join(f"{n:>16d}^3" for n in tet_sizes))

        def tline(label, **kw):
            medians(label, tet_sizes, grid="tet5", **kw)
        for t in sorted({1, threads}):
            tline(f"keymesh VERTEX-WELD, {t} thr", tool="keymesh", weld="vertexweld", threads=t)
            tline(f"keymesh KEY-REDUCE sort plan, {t} thr", tool="keymesh", weld="keyreduce", threads=t)
        tline(f"vtkContour3DLinearGrid, {threads} thr", tool="vtkContour3DLinearGrid")
        tline(f"keymesh tetrahedralize (CLI stage), {threads} thr", tool="keymesh-cli")
        for n in tet_sizes:
            kr = find(rows, size=n, grid="tet5", tool="keymesh", weld="keyreduce", threads=threads)
            vw = find(rows, size=n, grid="tet5", tool="keymesh", weld="vertexweld", threads=threads)
            vt = find(rows, size=n, grid="tet5", tool="vtkContour3DLinearGrid")
            parts = []
            if kr and vt:
                parts.append(f"vtkContour3DLinearGrid / keymesh {vt['median'] / kr['median']:.2f}x "
                             f"(triangles {kr['cells']} vs {vt['cells']})")
            if kr and vw:
                parts.append(f"VERTEX-WELD / KEY-REDUCE {vw['median'] / kr['median']:.2f}x")
            if kr:
                parts.append(f"keymesh peak RSS {kr['peak_rss_mib']:.0f} MiB")
            out(f"  {n}^3 tets, {threads} threads: " + "; ".join(parts))
    for bench_name, title, peer in (("subdivide", "Triangle subdivision 1 -> 4 of the sphere contour (Table 3)",
                                     "vtkLinearSubdivisionFilter"),
                                    ("tet24", "Face-centred tetrahedralization, 24 tets per voxel (Table 4)", None)):
        op_sizes = [n for n in sizes if find(rows, size=n, bench=bench_name)]
        if not op_sizes:
            continue
        out(f"\n{title}, warm medians (ms; min-max)")
        out(f"{'case':44s} " + " ".join(f"{n:>16d}^3" for n in op_sizes))

        def oline(label, **kw):
            medians(label, op_sizes, bench=bench_name, **kw)
        for t in sorted({1, threads}):
            oline(f"keymesh VERTEX-WELD, {t} thr", tool="keymesh", weld="vertexweld", threads=t)
            oline(f"keymesh KEY-REDUCE, {t} thr", tool="keymesh", weld="keyreduce", threads=t)
        if peer:
            oline(f"{peer}, 1 thr", tool=peer)
        for n in op_sizes:
            kr = find(rows, size=n, bench=bench_name, tool="keymesh", weld="keyreduce", threads=threads)
            vw = find(rows, size=n, bench=bench_name, tool="keymesh", weld="vertexweld", threads=threads)
            pr = find(rows, size=n, bench=bench_name, tool=peer) if peer else None
            parts = [f"{kr['cells']} cells"] if kr else []
            if kr and vw:
                parts.append(f"VERTEX-WELD / KEY-REDUCE {vw['median'] / kr['median']:.2f}x")
            if kr and pr:
                parts.append(f"{peer} / keymesh {pr['median'] / kr['median']:.2f}x")
            out(f"  {n}^3, {threads} threads: " + "; ".join(parts))
    op_sizes = [n for n in sizes if find(rows, size=n, bench="coarsen", tool="keymesh")]
    if op_sizes:
        out("\nCoarsening during the contour (Table 5) and the dual (Table 6), warm medians (ms; min-max)")
        out(f"{'case':44s} " + " ".join(f"{n:>16d}^3" for n in op_sizes))

        def cline(label, bench_name, **kw):
            medians(label, op_sizes, bench=bench_name, **kw)
        for t in sorted({1, threads}):
            cline(f"keymesh contour (ops_bench), {t} thr", "contour", tool="keymesh", threads=t, grid=None)
            cline(f"keymesh contour + coarsening, {t} thr", "coarsen", tool="keymesh", threads=t)
            cline(f"keymesh dual of the contour, {t} thr", "dual", tool="keymesh", threads=t)
        cline("vtkBinnedDecimation (bins = voxels), 1 thr", "coarsen", tool="vtkBinnedDecimation")
        cline("vtkQuadricClustering (bins = voxels), 1 thr", "coarsen", tool="vtkQuadricClustering")
        for n in op_sizes:
            c0 = find(rows, size=n, bench="contour", tool="keymesh", threads=threads, grid=None)
            c1 = find(rows, size=n, bench="coarsen", tool="keymesh", threads=threads)
            if c0 and c1:
                out(f"  {n}^3, {threads} threads: triangles {c0['cells']} -> {c1['cells']} "
                    f"({100 * (1 - c1['cells'] / c0['cells']):.0f}% removed); coarsening costs "
                    f"{100 * (c1['median'] / c0['median'] - 1):+.0f}% over the contour")
    peak = [r for r in rows if r.get("size") == sizes[-1] and r.get("grid") != "tet5" and r.get("bench") == "contour"
            and "input_points" not in r]
    out(f"\nPeak RSS at {sizes[-1]}^3 (MiB): " +
          ", ".join(f"{r['tool']} {r.get('weld', '')} {r.get('normals', '')} {r['peak_rss_mib']:.0f}".replace("  ", " ")
                    for r in peak if r.get("threads") == threads or r["tool"] == "vtkMarchingCubes"))
    return "\n".join(lines)


if __name__ == "__main__":
    main()
