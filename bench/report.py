#!/usr/bin/env python3
"""Turns bench/results/latest.jsonl into docs/RESULTS.md and the plots under
docs/results/ (matplotlib PNG). Run by bench/run.py at the end of `make bench`;
runnable alone:  python3 bench/report.py [--results bench/results/latest.jsonl]

Every measured figure comes from the results file (this run, this machine).
The paper's figures (Miller, Moreland and Ma, EGPGV 2014, Tables 1-6) are
quoted beside them, always labelled as the paper's; when the paper's text is
found (../shared/paper/history-based-topology.md from the repository), each
quoted number is checked against it first.
"""
import argparse
import json
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PAPER_FILE = os.path.join(os.path.dirname(ROOT), "shared", "paper", "history-based-topology.md")
PAPER_MACHINE = ("Intel Core i7 975 (3.33 GHz), 12 GB, 2 NVIDIA Tesla C2070; OpenMP with 8 threads "
                 "(the paper, Section 7)")

# The paper's tables, in ms (Table 1: counts). Keys: (dataset kind, size).
PAPER_T1 = {("sphere", 128): (149420, 10241915), ("sphere", 256): (607388, 82906875),
            ("sphere", 512): (2451212, None), ("mri", 128): (789440, 10241915),
            ("mri", 256): (4947294, 82906875), ("supernova", 432): (7036776, None)}
# Table 2: (VERTEX-WELD, KEY-REDUCE no merge, KEY-REDUCE averaging), per backend and grid
PAPER_T2 = {
    ("cuda", "voxel"): {("sphere", 128): (40, 31, 42), ("sphere", 256): (166, 141, 177),
                        ("sphere", 512): (847, 752, 894), ("mri", 128): (168, 138, 181),
                        ("mri", 256): (1092, 903, 1193), ("supernova", 432): (842, 723, 885)},
    ("cuda", "tet5"): {("sphere", 128): (242, 226, 251), ("sphere", 256): (1871, 1791, 2014),
                       ("mri", 128): (545, 476, 583), ("mri", 256): (4193, 4011, 4347)},
    ("openmp", "voxel"): {("sphere", 128): (184, 168, 191), ("sphere", 256): (652, 640, 721),
                          ("sphere", 512): (3266, 3254, 3582), ("mri", 128): (654, 634, 721),
                          ("mri", 256): (4022, 3090, 4851), ("supernova", 432): (3145, 3108, 3427)},
    ("openmp", "tet5"): {("sphere", 128): (816, 771, 901), ("sphere", 256): (9623, 9159, 10515),
                         ("mri", 128): (2123, 2117, 2514), ("mri", 256): (29425, 29224, 31429)},
}
# Table 3 and 4: (VERTEX-WELD, KEY-REDUCE)
PAPER_T3 = {"cuda": {("sphere", 128): (91, 84), ("sphere", 256): (362, 340), ("sphere", 512): (1443, 1367),
                     ("mri", 128): (479, 409), ("mri", 256): (3768, 3231), ("supernova", 432): (5798, 5514)},
            "openmp": {("sphere", 128): (360, 337), ("sphere", 256): (1410, 1304), ("sphere", 512): (5566, 5334),
                       ("mri", 128): (1532, 1376), ("mri", 256): (8905, 7939), ("supernova", 432): (13797, 13548)}}
PAPER_T4 = {"cuda": {("sphere", 128): (79, 75), ("sphere", 256): (624, 595), ("mri", 128): (152, 125),
                     ("mri", 256): (1219, 997)},
            "openmp": {("sphere", 128): (95, 77), ("sphere", 256): (766, 721), ("mri", 128): (215, 194),
                       ("mri", 256): (1994, 1781)}}
# Table 5 and 6: (CUDA, OpenMP), structured (voxel) rows
PAPER_T5 = {("sphere", 128): (41, 199), ("sphere", 256): (175, 725), ("sphere", 512): (885, 3571),
            ("mri", 128): (179, 729), ("mri", 256): (1150, 4875), ("supernova", 432): (717, 2958)}
PAPER_T6 = {("sphere", 128): (38, 100), ("sphere", 256): (138, 465), ("sphere", 512): (575, 1992),
            ("mri", 128): (203, 662), ("mri", 256): (1348, 4414)}


def check_paper():
    """Every quoted number must appear in the paper's text (when it is here)."""
    if not os.path.exists(PAPER_FILE):
        return f"not checked (the paper's text {PAPER_FILE} is not on this machine)"
    text = open(PAPER_FILE).read()
    found = set(re.findall(r"\d[\d,]*", text))
    missing = []

    def need(v, ms=True):
        if v is None:
            return
        s = f"{v:,}" if not ms else str(v)
        if s not in found:
            missing.append(s)
    for tris, tets in PAPER_T1.values():
        need(tris, False)
        need(tets, False)
    for table in (*PAPER_T2.values(), *PAPER_T3.values(), *PAPER_T4.values(), PAPER_T5, PAPER_T6):
        for vals in table.values():
            for v in vals:
                need(v)
    if missing:
        raise SystemExit(f"report.py: quoted paper figures not found in {PAPER_FILE}: {missing}")
    return f"checked against {os.path.relpath(PAPER_FILE, ROOT)}"


def kind(ds):
    return "sphere" if ds == "sphere" else ("supernova" if ds == "big432" else "mri")


def find(rows, **kw):
    for r in rows:
        if all((r.get(k) == v) if v is not None else (k not in r) for k, v in kw.items()):
            return r
    return None


def ms(r, spread=True):
    if not r:
        return "—"
    s = f"{r['median'] * 1e3:.1f}"
    if spread and "min" in r and r.get("reps", 1) > 1:
        s += f" ({r['min'] * 1e3:.1f}–{r['max'] * 1e3:.1f})"
    return s


def ratio(a, b):
    """b / a as 'x.xx×' (how many times faster a is than b), medians."""
    if not a or not b or not a.get("median") or not b.get("median"):
        return "—"
    return f"{b['median'] / a['median']:.2f}×"


RSS_CLEAN = True  # False for results of a run.py that built the datasets in its own process


def mib(r):
    if not r or "peak_rss_mib" not in r:
        return "—"
    if not RSS_CLEAN and r.get("dataset", "sphere") != "sphere":
        return "n/a"
    return f"{r['peak_rss_mib']:.0f}"


def table(head, body):
    out = ["| " + " | ".join(head) + " |", "|" + "|".join([" --- "] + [" ---: "] * (len(head) - 1)) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in body]
    return "\n".join(out)



def _num(x):
    """A load average as a float, 0 when the run did not record it."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return 0.0

class Report:
    def __init__(self, rows, results):
        self.rows = rows
        self.results = results
        self.run = find(rows, bench="run") or {}
        global RSS_CLEAN
        RSS_CLEAN = bool(self.run.get("rss_clean"))
        self.machine = rows[0].get("machine", {})
        self.T = max((r.get("threads", 1) for r in rows if r.get("tool") == "keymesh"), default=1)
        self.cases = []  # (dataset, size, label) in order
        for r in rows:
            if r.get("tool") == "keymesh" and r.get("bench") == "contour" and r.get("grid") == "voxel":
                c = (r["dataset"], r["size"])
                if c not in [x[:2] for x in self.cases]:
                    d = find(rows, bench="dataset", dataset=r["dataset"])
                    self.cases.append((*c, d["label"] if d else f"Spherical Distance {r['size']}³"))

    def q(self, ds, n, **kw):
        return find(self.rows, dataset=ds, size=n, **kw)

    def threads_of(self, ds, n, **kw):
        """The thread counts measured for this case (1 and all, or all only in QUICK runs)."""
        return [t for t in sorted({1, self.T}) if self.q(ds, n, threads=t, **kw)]

    def km(self, ds, n, weld="keyreduce", normals="none", threads=None, grid="voxel"):
        return self.q(ds, n, bench="contour", tool="keymesh", grid=grid, weld=weld, normals=normals,
                      threads=threads or self.T)

    def case_lines(self, **kw):
        """A table's lines: each case at each thread count measured (kw: the
        rows that count), as (dataset, size, label on the case's first line
        only, threads)."""
        for ds, n, label in self.cases:
            ts = self.threads_of(ds, n, **kw)
            for t in ts:
                yield ds, n, label if t == ts[0] else "", t

    def paper_columns(self, t, *quotes):
        """The paper's figures for a case ("VW/KR/avg" ms), on its all-threads line only."""
        return ["/".join(map(str, q)) if q and t == self.T else "" for q in quotes]

    # ---------------------------------------------------------------- sections
    def header(self):
        m, run = self.machine, self.run
        la0, la1 = run.get("loadavg_start", ["?"])[0], run.get("loadavg_end", ["?"])[0]
        return [
            "# keymesh benchmark results",
            "",
            f"Written by `bench/report.py` from `{os.path.relpath(self.results, ROOT)}`, the output of "
            f"`{run.get('command', 'make bench')}`. Every measured figure below comes from that one run "
            "(the working sessions' measurements by hand are in [results/NOTES.md](results/NOTES.md)); "
            "figures labelled *paper* are quoted from Miller, Moreland and Ma (EGPGV 2014), measured on "
            f"their machine: {PAPER_MACHINE}. Paper quotes {check_paper()}.",
            "",
            "## Machine and run",
            "",
            f"- **CPU:** {m.get('cpu')}, {m.get('cores')} cores; **memory:** {m.get('memory_gib')} GiB",
            f"- **Compiler:** {m.get('compiler')}; Linux {m.get('kernel')}",
            f"- **Date:** {m.get('date')}; **command:** `{run.get('command')}`; **duration:** "
            f"{run.get('seconds', 0) / 60:.1f} min",
            *self.durations(),
            f"- **Load average** (1 min) {la0} at the start, {la1} at the end; each row of "
            "`latest.jsonl` carries the load average when it was measured (`loadavg`). " +
            ("The VM is shared: other processes (compilers) competed for its cores during this run, so absolute "
             "times vary between runs and min–max spreads are wide; read ratios measured side by side, and "
             "minima beside medians." if max(_num(la0), _num(la1)) > 1.0 * (m.get("cores") or 1)
             else "Nothing but the benchmark ran during this run (its own processes make the load average)."),
            f"- **Repetitions:** {run.get('reps')} per case ({run.get('peer_reps')} for scikit-image and OpenVDB, "
            "and for VTK's contour filters on the 432³ case; 3 for tet24, 1 in QUICK runs); medians, with "
            "(min–max) in ms; stage times (classify, generate, weld, fields) are the last repetition's. Peak memory is the process's "
            "peak RSS (MiB), for peers the whole Python process including the interpreter and VTK.",
            *([] if RSS_CLEAN else [
                "- **Peak memory of the MRI rows is not reported (n/a)** for this run: bench/run.py resampled "
                "those volumes in its own process, and a child inherits its parent's peak-RSS high-water mark "
                "through fork and exec, so every program measured after that reported run.py's peak (1227 MiB "
                "for every 432³ row). Fixed since (datasets built in a separate process); the sphere rows ran "
                "before any dataset was built and are unaffected."]),
            f"- keymesh and Thrust run with `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`, as do the VTK peers.",
            "",
        ]

    def durations(self):
        """Today's run durations, from bench/results/durations.jsonl (run.py appends one line per run)."""
        path = os.path.join(os.path.dirname(self.results), "durations.jsonl")
        if not os.path.exists(path):
            return []
        today = [json.loads(line) for line in open(path) if line.strip()]
        today = [d for d in today if d.get("date") == self.machine.get("date")]
        if not today:
            return []
        return ["- **Run durations today** (`bench/results/durations.jsonl`): " + "; ".join(
            f"`{d['command']}` at {d['time']}: {d['seconds'] / 60:.1f} min (load {d['loadavg_start'][0]:.1f} → "
            f"{d['loadavg_end'][0]:.1f})" for d in today)]

    def table1(self):
        body = []
        for ds, n, label in self.cases:
            kr = self.km(ds, n)
            tets = self.q(ds, n, bench="contour", tool="keymesh", grid="tet5", weld="keyreduce", threads=self.T)
            tg = self.q(ds, n, bench="tetrahedralize", tool="keymesh-cli")
            p = PAPER_T1.get((kind(ds), n), (None, None))
            iso = kr["iso"] if kr else None
            body.append([label, f"{n}³", f"{iso:g}" if iso is not None else "—",
                         f"{kr['cells']:,}" if kr else "—", f"{kr['points']:,}" if kr else "—",
                         f"{tg['cells']:,}" if tg else "not run",
                         f"{tets['cells']:,}" if tets else "—",
                         f"{p[0]:,}" if p[0] else "—", f"{p[1]:,}" if p[1] else "N/A"])
        ds_rows = [r for r in self.rows if r.get("bench") == "dataset"]
        notes = [f"- **{r['dataset']}**: {r['label']}; source `{r['source']}`; resampling {r['resampling']}."
                 for r in ds_rows]
        return ["## Table 1: datasets", "",
                "Isovalues are non-integer. The paper's MRI head and supernova volumes are not available; "
                "ours come from Debian packages (built by `bench/datasets.py` at bench time), so their "
                "triangle counts differ from the paper's.", "",
                table(["dataset", "dims", "isovalue", "triangles", "points", "tets (5-tet grid)",
                       "tet-contour triangles", "paper: triangles", "paper: tets"], body), "", *notes, ""]

    def table2(self):
        T = self.T
        out = ["## Table 2: marching cubes with vertex welding", "",
               "keymesh in-process (`bench/contour_bench`, no file I/O): VERTEX-WELD (the soup welded by "
               "coordinates), KEY-REDUCE sort plan and dense plan without merge, and KEY-REDUCE averaging "
               "the normals. Peers on the same volume, timing only their contour call. *Paper* columns: "
               "their OpenMP (8 threads) and CUDA (Tesla C2070) times for VERTEX-WELD / KEY-REDUCE / "
               "averaging.", ""]
        body = []
        for ds, n, shown, t in self.case_lines(bench="contour", tool="keymesh", grid="voxel"):
            pk = (kind(ds), n)
            po, pc = PAPER_T2[("openmp", "voxel")].get(pk), PAPER_T2[("cuda", "voxel")].get(pk)
            vw, srt = self.km(ds, n, "vertexweld", threads=t), self.km(ds, n, "keyreduce-sort", threads=t)
            kr, av = self.km(ds, n, threads=t), self.km(ds, n, normals="average", threads=t)
            body.append([shown, t, ms(vw), ms(srt), ms(kr), ms(av), ratio(kr, vw),
                         f"{100 * (av['median'] / kr['median'] - 1):+.0f}%" if kr and av else "—",
                         mib(kr), *self.paper_columns(t, po, pc)])
        out += [table(["dataset", "thr", "VERTEX-WELD", "KEY-REDUCE sort", "KEY-REDUCE dense", "KEY-REDUCE avg",
                       "VW / KR", "avg overhead", "KR peak MiB", "paper OpenMP ms", "paper CUDA ms"], body), ""]
        # peers
        out += ["### Peers (same volume, same isovalue)", "",
                "Ratio = peer median / keymesh KEY-REDUCE dense plan (no merge) median at "
                f"{T} threads; above 1 means keymesh is faster. Thrust is Bell's VERTEX-WELD (sort, unique, "
                "lower_bound of the soup's positions) on Thrust's OpenMP backend, and vtkCleanPolyData "
                "(tolerance 0) welds the same soup with VTK's point locator; both time the weld alone, so they "
                "are set beside keymesh VERTEX-WELD's weld stage (`weld_s`) too. scikit-image is "
                "single-threaded and also computes normals; OpenVDB meshes dually (a point per cut voxel, "
                "quads counted as 2 triangles) on all cores through TBB.", ""]
        body = []
        peers = [("vtkFlyingEdges3D", "vtkFlyingEdges3D"), ("vtkMarchingCubes", "vtkMarchingCubes"),
                 ("skimage-marching_cubes", "scikit-image marching_cubes (lorensen)"),
                 ("openvdb-volumeToMesh", "OpenVDB volumeToMesh"),
                 ("thrust-vertexweld", "Thrust VERTEX-WELD (weld only)"),
                 ("vtkCleanPolyData", "vtkCleanPolyData on the soup (weld only)")]
        for ds, n, label in self.cases:
            kr = self.km(ds, n)
            for tool, name in peers:
                p = self.q(ds, n, bench="contour", tool=tool, grid=None)
                if tool == "thrust-vertexweld":
                    p = self.q(ds, n, bench="contour", tool=tool)
                if not p:
                    continue
                extra, rat = "", ratio(kr, p)
                if tool in ("thrust-vertexweld", "vtkCleanPolyData"):
                    # weld only: against keymesh's weld stages (last repetition's stage times)
                    vw = self.km(ds, n, "vertexweld")
                    if kr and kr.get("weld_s"):
                        rat = f"{p['median'] / kr['weld_s']:.2f}× (vs KR weld stage {kr['weld_s'] * 1e3:.1f} ms)"
                    if vw:
                        extra = (f"keymesh VERTEX-WELD weld stage {vw['weld_s'] * 1e3:.1f} ms: "
                                 f"{p['median'] / vw['weld_s']:.2f}×; whole KR contour {ratio(kr, p)}")
                body.append([label, name, p.get("threads", 1), ms(p), f"{p['cells']:,}", mib(p), rat, extra])
            cli, fec = self.q(ds, n, tool="keymesh-cli"), self.q(ds, n, tool="vtkFlyingEdges3D-cold")
            if cli and fec:
                body.append([label, "one-shot: keymesh CLI `seconds.contour` vs vtkFlyingEdges3D fresh process",
                             T, f"{ms(cli, False)} vs {ms(fec, False)}", "", f"{mib(cli)} vs {mib(fec)}",
                             ratio(cli, fec), "fresh process per run, median"])
        out += [table(["dataset", "peer", "thr", "peer ms", "triangles", "peer MiB", "peer / keymesh", "note"],
                      body), ""]
        # tets
        body = []
        for ds, n, shown, t in self.case_lines(bench="contour", tool="keymesh", grid="tet5"):
            if not self.km(ds, n, grid="tet5"):
                continue
            pk = (kind(ds), n)
            po, pc = PAPER_T2[("openmp", "tet5")].get(pk), PAPER_T2[("cuda", "tet5")].get(pk)
            vt = self.q(ds, n, bench="contour", grid="tet5", tool="vtkContour3DLinearGrid")
            vw, k = self.km(ds, n, "vertexweld", threads=t, grid="tet5"), self.km(ds, n, threads=t, grid="tet5")
            body.append([shown, t, ms(vw), ms(k), ratio(k, vw), mib(k),
                         ms(vt) if t == self.T else "", ratio(k, vt) if t == self.T else "",
                         *self.paper_columns(t, po, pc)])
        if body:
            out += ["### Unstructured: marching tetrahedra on the 5-tet grid", "",
                    "keymesh keys a point by its edge's two point ids (KEY-REDUCE sort plan); the tet grid is "
                    "built once outside the timing. vtkContour3DLinearGrid (point merging on) reads keymesh's "
                    "`.vtu` of the same grid. *Paper*: VERTEX-WELD / KEY-REDUCE / averaging.", "",
                    table(["dataset", "thr", "VERTEX-WELD", "KEY-REDUCE", "VW / KR", "KR peak MiB",
                           "vtkContour3DLinearGrid", "VTK / keymesh", "paper OpenMP ms", "paper CUDA ms"], body),
                    ""]
        return out

    def op_table(self, bench, title, intro, paper, peer=None):
        body = []
        for ds, n, shown, t in self.case_lines(bench=bench, tool="keymesh"):
            pk = (kind(ds), n)
            po, pc = paper["openmp"].get(pk), paper["cuda"].get(pk)
            p = self.q(ds, n, bench=bench, tool=peer) if peer else None
            vw = self.q(ds, n, bench=bench, tool="keymesh", weld="vertexweld", threads=t)
            kr = self.q(ds, n, bench=bench, tool="keymesh", weld="keyreduce", threads=t)
            row = [shown, t, f"{kr['cells']:,}" if kr else "—", ms(vw), ms(kr), ratio(kr, vw), mib(kr)]
            if peer:
                row += [ms(p) if t == self.T else "", ratio(kr, p) if t == self.T else ""]
            row += self.paper_columns(t, po, pc)
            body.append(row)
        head = ["dataset", "thr", "output cells", "VERTEX-WELD", "KEY-REDUCE", "VW / KR", "KR peak MiB"]
        if peer:
            head += [f"{peer} (1 thr)", "peer / keymesh"]
        head += ["paper OpenMP VW/KR ms", "paper CUDA VW/KR ms"]
        return [f"## {title}", "", intro, "", table(head, body), ""]

    def table5_6(self):
        out = ["## Table 5: marching cubes with coarsening", "",
               "`bench/ops_bench --op coarsen` (contour with every crossing keyed by its nearest grid point, "
               "positions averaged, collapsed triangles and folds removed) against `--op contour` (the same "
               "contour, scalars carried, no normals). Peers decimate the finished contour with one bin per "
               "voxel (their time excludes the contour). *Paper*: OpenMP / CUDA, structured.", ""]
        body = []
        for ds, n, shown, t in self.case_lines(bench="coarsen", tool="keymesh"):
            p5 = PAPER_T5.get((kind(ds), n))
            bd = self.q(ds, n, bench="coarsen", tool="vtkBinnedDecimation")
            qc = self.q(ds, n, bench="coarsen", tool="vtkQuadricClustering")
            c0 = self.q(ds, n, bench="contour", tool="keymesh", threads=t, grid=None)
            c1 = self.q(ds, n, bench="coarsen", tool="keymesh", threads=t)
            body.append([shown, t, ms(c0), ms(c1),
                         f"{100 * (c1['median'] / c0['median'] - 1):+.0f}%" if c0 else "—",
                         f"{c0['cells']:,} → {c1['cells']:,}" if c0 else "—", mib(c1),
                         ms(bd) if t == self.T else "", ms(qc) if t == self.T else "",
                         *self.paper_columns(t, p5 and p5[::-1])])
        out += [table(["dataset", "thr", "contour", "contour + coarsening", "coarsening cost", "triangles",
                       "peak MiB", "vtkBinnedDecimation", "vtkQuadricClustering", "paper OpenMP/CUDA ms"], body),
                "", "Not run: coarsening of the marching-tetrahedra contour (the paper's unstructured rows).", ""]
        out += ["## Table 6: dual mesh of the contour", "",
                "`bench/ops_bench --op dual`: the dual of the contour with averaged normals (a polygon per point "
                "through its triangles' centroids, keyed by the point). *Paper*: OpenMP / CUDA, structured.", ""]
        body = []
        for ds, n, shown, t in self.case_lines(bench="dual", tool="keymesh"):
            p6 = PAPER_T6.get((kind(ds), n))
            d = self.q(ds, n, bench="dual", tool="keymesh", threads=t)
            body.append([shown, t, f"{d['input_cells']:,}", f"{d['cells']:,}", ms(d), mib(d),
                         *self.paper_columns(t, p6 and p6[::-1])])
        out += [table(["dataset", "thr", "input triangles", "dual polygons", "dual", "peak MiB",
                       "paper OpenMP/CUDA ms"], body),
                "", "Not run: the dual of the marching-tetrahedra contour (the paper's unstructured rows).", ""]
        return out

    def headlines(self):
        T = self.T
        out = ["## Headline ratios (this run)", ""]
        big = [c for c in self.cases if c[0] == "sphere"]
        if big:
            ds, n, _ = big[-1]
            kr, fe = self.km(ds, n), self.q(ds, n, bench="contour", tool="vtkFlyingEdges3D", grid=None)
            vw, av = self.km(ds, n, "vertexweld"), self.km(ds, n, normals="average")
            cli, fec = self.q(ds, n, tool="keymesh-cli"), self.q(ds, n, tool="vtkFlyingEdges3D-cold")
            c0 = self.q(ds, n, bench="contour", tool="keymesh", threads=T, grid=None)
            c1 = self.q(ds, n, bench="coarsen", tool="keymesh", threads=T)
            if kr and fe:
                out.append(f"- Sphere {n}³, {T} threads, contour: vtkFlyingEdges3D / keymesh KEY-REDUCE "
                           f"**{fe['median'] / kr['median']:.2f}×** (medians {fe['median'] * 1e3:.1f} / "
                           f"{kr['median'] * 1e3:.1f} ms; minima {fe['min'] / kr['min']:.2f}×)")
            if cli and fec:
                out.append(f"- Sphere {n}³ one-shot: vtkFlyingEdges3D fresh process / keymesh CLI "
                           f"`seconds.contour` **{fec['median'] / cli['median']:.2f}×**")
            if kr and vw:
                out.append(f"- Sphere {n}³: VERTEX-WELD / KEY-REDUCE **{vw['median'] / kr['median']:.2f}×**")
            if kr and av:
                out.append(f"- Sphere {n}³: averaging overhead **{100 * (av['median'] / kr['median'] - 1):+.0f}%** "
                           f"(medians), {100 * (av['min'] / kr['min'] - 1):+.0f}% (minima)")
            if c0 and c1:
                out.append(f"- Sphere {n}³: coarsening overhead **{100 * (c1['median'] / c0['median'] - 1):+.0f}%** "
                           f"(medians), {100 * (c1['min'] / c0['min'] - 1):+.0f}% (minima)")
        for ds, n, label in self.cases:
            k, vt = self.km(ds, n, grid="tet5"), self.q(ds, n, bench="contour", grid="tet5",
                                                          tool="vtkContour3DLinearGrid")
            if k and vt:
                out.append(f"- {label} tets: vtkContour3DLinearGrid / keymesh "
                           f"**{vt['median'] / k['median']:.2f}×**")
        out.append("")
        return out

    def losses(self):
        """Every case where a peer's median beats keymesh's at all threads."""
        out = []
        T = self.T
        for ds, n, label in self.cases:
            kr = self.km(ds, n)
            for r in self.rows:
                if r.get("dataset") != ds or r.get("size") != n or r.get("tool") in (None, "keymesh") or \
                        "median" not in r:
                    continue
                base = None
                if r["tool"].endswith("-cold") or r["tool"] == "keymesh-cli":
                    base = self.q(ds, n, tool="keymesh-cli") if r["tool"].endswith("-cold") else None
                elif r.get("bench") == "contour" and r.get("grid") is None:
                    base = kr
                elif r.get("bench") == "contour" and r.get("grid") == "tet5":
                    base = self.km(ds, n, grid="tet5")
                elif r.get("bench") == "subdivide":
                    base = self.q(ds, n, bench="subdivide", tool="keymesh", weld="keyreduce", threads=T)
                elif r.get("bench") == "coarsen":
                    # the peers decimate a finished contour: set them beside what
                    # coarsening adds to keymesh's contour (difference of medians)
                    c0 = self.q(ds, n, bench="contour", tool="keymesh", threads=T, grid=None)
                    c1 = self.q(ds, n, bench="coarsen", tool="keymesh", threads=T)
                    if c0 and c1 and c1["median"] - c0["median"] > r["median"]:
                        out.append(f"- {label}, coarsening: **{r['tool']}** decimates the finished contour in "
                                   f"{r['median'] * 1e3:.1f} ms; keymesh's coarsening adds "
                                   f"{(c1['median'] - c0['median']) * 1e3:.1f} ms to its contour (medians "
                                   f"{c1['median'] * 1e3:.1f} − {c0['median'] * 1e3:.1f} ms, {T} threads, load "
                                   f"{c1.get('loadavg')}); keymesh's output keeps every surface point's history "
                                   "(fields averaged per grid point), the peers' bins do not")
                    continue
                elif r["tool"] in ("thrust-vertexweld", "vtkCleanPolyData"):
                    base = kr
                if base and r["median"] < base["median"]:
                    st = ""
                    if all(k in base for k in ("classify", "generate", "weld_s", "fields")):
                        st = (f"; keymesh stages: classify {base['classify'] * 1e3:.1f}, generate "
                              f"{base['generate'] * 1e3:.1f}, weld {base['weld_s'] * 1e3:.1f}, fields "
                              f"{base['fields'] * 1e3:.1f} ms (stage times of the last repetition)")
                    one = self.q(ds, n, bench=base.get("bench"), tool="keymesh", grid=base.get("grid"),
                                 weld=base.get("weld"), normals=base.get("normals"), threads=1) \
                        if base.get("tool") == "keymesh" and T > 1 else None
                    one_s = (f"; keymesh at 1 thread {one['median'] * 1e3:.1f} ms"
                             if one and base.get("threads") != 1 else "")
                    out.append(f"- {label}, {r['bench']}: **{r['tool']}** ({r.get('threads', 1)} thr) "
                               f"{r['median'] * 1e3:.1f} ms against keymesh {base['median'] * 1e3:.1f} ms at "
                               f"{base.get('threads', T)} thr (min {r['min'] * 1e3:.1f} vs {base['min'] * 1e3:.1f}; "
                               f"load {base.get('loadavg', '?')} / {r.get('loadavg', '?')}){one_s}{st}")
        for ds, n, label in self.cases:
            act = self.km(ds, n)
            pas = self.q(ds, n, bench="contour", tool="keymesh", weld="keyreduce-passive")
            one = self.km(ds, n, threads=1)
            if act and pas:
                out.append(f"- {label}, contour at {T} threads with libgomp's default waiting (threads spin at "
                           f"barriers) {act['median'] * 1e3:.1f} ms (min {act['min'] * 1e3:.1f}), with "
                           f"`OMP_WAIT_POLICY=passive` {pas['median'] * 1e3:.1f} ms (min {pas['min'] * 1e3:.1f}), "
                           f"at 1 thread {one['median'] * 1e3:.1f} ms (load {act.get('loadavg')} / "
                           f"{pas.get('loadavg')}). keymesh splits every parallel step into fixed chunks, one per "
                           "thread, and waits at a barrier for the slowest; when other processes hold a core, "
                           "the waiting thread spins and the descheduled one finishes late. VTK's TBB backend "
                           "steals work instead. On a quiet machine the default is the faster one.")
        head = ["## Where keymesh loses", "",
                "Cases in this run where a peer's median is below keymesh's at the same thread count "
                "(keymesh at all threads; peers as noted above). Listed from the results file, with keymesh's "
                "stage times and the load average when each side was measured.", ""]
        return head + (out or ["- none in this run"]) + [""]

    def skipped(self):
        sk = [r for r in self.rows if r.get("bench") == "skipped"]
        seen, out = set(), []
        for r in sk:
            if (r["tool"], r["reason"]) in seen:
                continue
            seen.add((r["tool"], r["reason"]))
            out.append(f"- {r['tool']}: {r['reason']}")
        return ["## Peers or pictures not run", ""] + (out or ["- none: every peer ran"]) + [""]

    def figures(self, plots):
        out = ["## Plots", ""]
        for path, caption in plots:
            out += [f"![{caption}]({os.path.relpath(path, os.path.join(ROOT, 'docs'))})", "", f"*{caption}*", ""]
        figs = [r for r in self.rows if r.get("bench") == "figure"]
        if figs:
            out += ["## Pictures (the paper's Figures 8–10)", "",
                    "Rendered off-screen with VTK (`bench/figures.py`) from keymesh's output in this run.", ""]
            for r in figs:
                cap = {8: lambda: f"Figure 8 analogue: {r['dataset']} after `keymesh pipeline --coarsen --curvature "
                          f"--subdivide 1` ({r['cells']:,} triangles), coloured by mean curvature (red high, blue "
                          f"low; ±{r['curvature_range_shown'][1]:.2f}, the 5th–95th percentile)",
                       9: lambda: f"Figure 9 analogue: a coarse sphere contour ({r['input_cells']} triangles, left) and its "
                          f"Bezier (PN triangle) subdivision, 2 levels ({r['cells']:,} triangles, right)",
                       10: lambda: f"Figure 10 analogue: the dual mesh ({r['cells']:,} polygons, blue) over its contour "
                           f"({r['input_cells']:,} triangles, green), Spherical Distance 24³, iso {r['iso']}"}
                png = os.path.join(ROOT, r["png"])
                c = cap[r["figure"]]()
                out += [f"![{c}]({os.path.relpath(png, os.path.join(ROOT, 'docs'))})", "", f"*{c}*", ""]
        return out

    # ---------------------------------------------------------------- plots
    def plots(self, outdir):
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            self.rows.append({"bench": "skipped", "tool": "plots", "reason": "python3-matplotlib is not installed"})
            return []
        os.makedirs(outdir, exist_ok=True)
        T, made = self.T, []

        def save(fig, name, caption):
            path = os.path.join(outdir, name)
            fig.tight_layout()
            fig.savefig(path, dpi=80)
            plt.close(fig)
            made.append((path, caption))

        # time against size (output triangles), every dataset, log-log
        fig, ax = plt.subplots(figsize=(7, 4.5))
        series = [("keymesh KEY-REDUCE", dict(bench="contour", tool="keymesh", grid="voxel", weld="keyreduce",
                                              normals="none", threads=T), "o-"),
                  ("keymesh KEY-REDUCE, 1 thread", dict(bench="contour", tool="keymesh", grid="voxel",
                                                        weld="keyreduce", normals="none", threads=1), "o:"),
                  ("keymesh VERTEX-WELD", dict(bench="contour", tool="keymesh", grid="voxel", weld="vertexweld",
                                               threads=T), "s--"),
                  ("vtkFlyingEdges3D", dict(bench="contour", tool="vtkFlyingEdges3D", grid=None), "^-"),
                  ("vtkMarchingCubes", dict(bench="contour", tool="vtkMarchingCubes", grid=None), "v-"),
                  ("scikit-image", dict(bench="contour", tool="skimage-marching_cubes", grid=None), "d-"),
                  ("OpenVDB", dict(bench="contour", tool="openvdb-volumeToMesh", grid=None), "x-"),
                  ("Thrust VERTEX-WELD (weld only)", dict(bench="contour", tool="thrust-vertexweld"), "+-")]
        for name, kw, style in series:
            pts = []
            for ds, n, _ in self.cases:
                r = self.q(ds, n, **kw)
                kr = self.km(ds, n)
                if r and kr:
                    pts.append((kr["cells"], r["median"] * 1e3))
            if pts:
                pts.sort()
                ax.plot(*zip(*pts), style, label=name)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("output triangles (all datasets)")
        ax.set_ylabel("median time (ms)")
        ax.set_title(f"Marching cubes + weld, {T} threads where threaded")
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        save(fig, "time-vs-size.png", "Time against output size, keymesh and peers (log-log, medians)")

        # speed-up 1 -> T threads per operation, largest case of each dataset
        if T > 1:
            labels, vals = [], []
            for ds, n, label in self.cases:
                for nm, kw in (("KR", dict(bench="contour", tool="keymesh", grid="voxel", weld="keyreduce",
                                           normals="none")),
                               ("KR avg", dict(bench="contour", tool="keymesh", grid="voxel", weld="keyreduce",
                                               normals="average")),
                               ("VW", dict(bench="contour", tool="keymesh", grid="voxel", weld="vertexweld")),
                               ("subdiv", dict(bench="subdivide", tool="keymesh", weld="keyreduce")),
                               ("coarsen", dict(bench="coarsen", tool="keymesh")),
                               ("dual", dict(bench="dual", tool="keymesh"))):
                    a, b = self.q(ds, n, threads=1, **kw), self.q(ds, n, threads=T, **kw)
                    if a and b:
                        labels.append(f"{ds} {n}\n{nm}")
                        vals.append(a["median"] / b["median"])
            fig, ax = plt.subplots(figsize=(max(7, 0.32 * len(vals)), 4))
            ax.bar(range(len(vals)), vals, color="tab:blue")
            ax.axhline(T, color="gray", ls="--", lw=1, label=f"ideal ({T}×)")
            ax.axhline(1, color="black", lw=0.8)
            ax.set_xticks(range(len(vals)))
            ax.set_xticklabels(labels, rotation=90, fontsize=6)
            ax.set_ylabel(f"speed-up 1 → {T} threads (medians)")
            ax.legend(fontsize=8)
            save(fig, "speedup-threads.png", f"keymesh speed-up from 1 to {T} threads, per dataset and operation")

        # keymesh against peers: ratio peer / keymesh per dataset
        fig, ax = plt.subplots(figsize=(8, 4.2))
        peers = [("vtkFlyingEdges3D", dict(bench="contour", tool="vtkFlyingEdges3D", grid=None)),
                 ("vtkMarchingCubes", dict(bench="contour", tool="vtkMarchingCubes", grid=None)),
                 ("scikit-image", dict(bench="contour", tool="skimage-marching_cubes", grid=None)),
                 ("OpenVDB", dict(bench="contour", tool="openvdb-volumeToMesh", grid=None)),
                 ("Thrust weld", dict(bench="contour", tool="thrust-vertexweld"))]
        width = 0.8 / len(peers)
        for i, (name, kw) in enumerate(peers):
            xs, ys = [], []
            for j, (ds, n, _) in enumerate(self.cases):
                r, kr = self.q(ds, n, **kw), self.km(ds, n)
                if r and kr:
                    xs.append(j + i * width)
                    ys.append(r["median"] / kr["median"])
            ax.bar(xs, ys, width, label=name)
        ax.axhline(1, color="black", lw=0.8)
        ax.set_yscale("log")
        ax.set_xticks([j + 0.4 - width / 2 for j in range(len(self.cases))])
        ax.set_xticklabels([f"{ds}\n{n}³" for ds, n, _ in self.cases], fontsize=8)
        ax.set_ylabel("peer time / keymesh KEY-REDUCE time")
        ax.set_title(f"keymesh against peers (above 1: keymesh faster; keymesh at {T} threads)")
        ax.legend(fontsize=7)
        save(fig, "keymesh-vs-peers.png", "Peer median / keymesh KEY-REDUCE median, per dataset (log scale)")
        return made

    def labels_table(self):
        rows = [r for r in self.rows if r.get("bench") == "labels"]
        if not rows:
            return []
        fe = next((r for r in rows if r["case"].startswith("vtk")), None)
        body = [[r["case"], r["threads"], f"{r['seconds']:.3f}", f"{r['points']:,}" if "points" in r else "",
                 f"{r['triangles']:,}" if "triangles" in r else "",
                 f"{fe['seconds'] / r['seconds']:.1f}×" if fe and not r["case"].startswith(("vtk", "smoothing")) else "",
                 r["loadavg"]] for r in rows]
        return ["## Label maps (issue 18)", "",
                f"`bench/labels_bench.py`: the AAL atlas ({rows[0]['labels']} labels, all of them), in one process: "
                "`keymesh.contour_labels` without smoothing against vtkDiscreteFlyingEdges3D with one contour value "
                "per label; the smoothing stage alone below. Medians after a warm-up.", "",
                table(["case", "thr", "seconds", "points", "triangles", "VTK / keymesh", "load"], body), ""]

    def lods_table(self):
        rows = [r for r in self.rows if r.get("bench") == "lods"]
        if not rows:
            return []
        body = [[r["case"], r["threads"], f"{r['seconds']:.3f}", f"{r['mvox_per_s']:.1f}",
                 " / ".join(f"{t:,}" for t in r["triangles"]),
                 f"{r['labels_stage']:.3f}" if "labels_stage" in r else "",
                 f"{r['write_stage']:.3f}" if "write_stage" in r else "", r["loadavg"]] for r in rows]
        return ["## Multi-resolution label meshes (issue 37)", "",
                "`bench/lods_bench.py`: the AAL atlas to Neuroglancer's multi-resolution format "
                "(`keymesh labels --format precomputed`, 32^3 chunks, Draco) in a fresh process per run, against "
                "vtkDiscreteFlyingEdges3D and vtkQuadricDecimation to keymesh's per-level triangle counts in one "
                "process (no smoothing, no file). Medians after a warm-up.", "",
                table(["case", "thr", "seconds", "Mvox/s", "triangles per level", "labels stage s", "write stage s",
                       "load"], body), ""] + self.lods_per_level(rows)

    @staticmethod
    def lods_per_level(rows):
        level0 = next((r for r in rows if r["case"].startswith("keymesh --lods 1")), None)
        all3 = next((r for r in rows if r["case"] == "keymesh --lods 3"), None)
        if not level0 or not all3 or "per_level_ratio_median" not in all3:
            return []
        extra = (all3["seconds"] - level0["seconds"]) / 2
        lo, hi = all3["per_level_ratio_range"]
        return [f"Each coarser level: {extra:.3f} s, {100 * extra / level0['seconds']:.1f} % of level 0's run "
                f"(medians); per round (runs of both seconds apart): median {100 * all3['per_level_ratio_median']:.1f} %, "
                f"{100 * lo:.1f} to {100 * hi:.1f} %.", ""]

    def dense_table(self):
        rows = [r for r in self.rows if r.get("bench") == "dense" and "median" in r]
        if not rows:
            return []
        body = []
        for case in dict.fromkeys(r["case"] for r in rows):
            for huge in (True, False):
                km = next((r for r in rows if r["case"] == case and r["tool"] == "keymesh" and r["huge_pages"] == huge), None)
                fe = next((r for r in rows if r["case"] == case and r["tool"] == "vtkFlyingEdges3D"
                           and r["huge_pages"] == huge), None)
                if not km:
                    continue
                cpp = next((r for r in rows if r["case"] == case and r["tool"] == "contour_bench"
                            and r.get("huge_pages", True) == huge), None)
                fe_cpp = cpp.get("fe3d_median") if cpp else None
                body.append([km["label"] + (f", {len(km['isovalues'])} isovalues" if len(km["isovalues"]) > 1 else ""),
                             "on" if huge else "off", f"{km['cells']:,}", f"{km['median'] * 1e3:.1f}",
                             f"{fe['median'] * 1e3:.1f}" if fe else "", f"{fe['median'] / km['median']:.2f}×" if fe else "",
                             f"{cpp['median'] * 1e3:.1f}" if cpp else "",
                             f"{fe_cpp / cpp['median']:.2f}×" if fe_cpp else "",
                             f"{km['sum_single'] / km['median']:.2f}" if km.get("sum_single") else "",
                             f"{km['input_mib']:.0f} + {km['output_mib']:.0f}" if "output_mib" in km else "",
                             f"{cpp['peak_rss_mib']:.0f}" if cpp else "", km.get("loadavg", "")])
        return ["## Real and dense volumes (issue 17)", "",
                "`bench/dense.py`: `keymesh.contour` (Python module, fresh output arrays, `normals=\"none\"`, "
                "`scalars=False`) and vtkFlyingEdges3D (normals, gradients and scalars off) in one process on the "
                "same array: positions and triangles only, in both; "
                f"{rows[0]['threads']} threads, medians after a warm-up; with huge pages "
                "(`glibc.malloc.hugetlb=1` for the whole process) and without (a Python process's default "
                "malloc; keymesh still asks `madvise` for its output arrays). C++ harness: `bench/contour_bench` "
                "on the same volume with the same huge-pages setting (`KEYMESH_HUGE_PAGES=0` without), and "
                "FE3D / C++ harness: " + (
                    "vtkFlyingEdges3D in the harness's own process on the same samples (`--peer fe3d`, each "
                    "tool's calls in two blocks), its median over keymesh's" if any(r.get("fe3d_same_process") for r in self.rows
                                                                      if r.get("tool") == "contour_bench") else
                    "the FE3D median of that setting's Python run over the harness's median (this harness was "
                    "built without VTK's C++ package, libvtk9-dev: FE3D ran in the Python process)") +
                ". Several isovalues: the sum of the single-isovalue medians over "
                "the one-call median (≥ 1: one call costs no more). Memory: input + output MiB of the call, and the "
                "C++ harness's peak RSS (the whole process: volume read, contour, output). The working sessions' "
                "measurements of these volumes, by hand, are in [results/NOTES.md](results/NOTES.md).", "",
                table(["volume", "huge pages", "triangles", "keymesh ms", "FE3D ms", "FE3D / keymesh", "C++ harness ms",
                       "FE3D / C++ harness",
                       "Σ single / one call", "input + output MiB", "harness peak MiB", "load"], body), ""]

    def write(self, path, plotdir):
        plots = self.plots(plotdir)
        parts = (self.header() + self.headlines() + self.table1() + self.table2() +
                 self.op_table("subdivide", "Table 3: one level of triangle subdivision (1 → 4)",
                               "`bench/ops_bench --op subdivide` on the contour with averaged normals: new points "
                               "keyed by their parent edge (KEY-REDUCE) or welded by coordinates (VERTEX-WELD).",
                               PAPER_T3, "vtkLinearSubdivisionFilter") +
                 self.op_table("tet24", "Table 4: face-centred tetrahedralization (24 tets per voxel)",
                               "`bench/ops_bench --op tet24`: face centres keyed by the face (KEY-REDUCE) or welded "
                               "by coordinates (VERTEX-WELD); run up to 128³ (49 M tets). Data-independent: the "
                               "MRI row times the same grid shape.", PAPER_T4) +
                 self.table5_6() + self.dense_table() + self.labels_table() + self.lods_table() + self.losses() + self.skipped() + self.figures(plots))
        # The whole file is this run's; measurements by hand live in
        # docs/results/NOTES.md, which no bench run touches.
        parts += ["## Measured by hand", "",
                  "The working sessions' own measurements, each with its date and command: "
                  "[results/NOTES.md](results/NOTES.md).", ""]
        text = "\n".join(parts).rstrip() + "\n"
        with open(path + ".tmp", "w") as f:
            f.write(text)
        os.replace(path + ".tmp", path)
        return path



def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", default=os.path.join(HERE, "results", "latest.jsonl"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "RESULTS.md"))
    ap.add_argument("--plots", default=os.path.join(ROOT, "docs", "results"))
    a = ap.parse_args()
    rows = [json.loads(line) for line in open(a.results)]
    if not rows:
        sys.exit("report.py: no results")
    print(f"report: {Report(rows, a.results).write(a.out, a.plots)}")


if __name__ == "__main__":
    main()
