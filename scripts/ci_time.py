"""Where CI's `make test` spends its time (docs/decisions/ci-time.md).

Clones the repository at a revision into a fresh folder and runs the phases
of `CI=true make test` there one after the other, as the Makefile does:
`make build`, `make gltf-validator`, `ctest -j JOBS`, `make sanitize-quick`,
each under `nice -n 19` without ccache (CCACHE_DISABLE=1). For each phase it
records the wall time and the CPU time (user + system of every process it
ran); the CPU times hardly change with the machine's load, the wall times do.
Every compile and link step goes through this script as CMake's compiler and
linker launcher, which records its CPU time, so the report names the heaviest
sources and targets of both builds; ctest's own cost data names the slowest
tests.

    /usr/bin/python3 scripts/ci_time.py --rev HEAD --clone /work/ci-time-clone [--cuda]

--cuda keeps the CUDA backend when nvcc is found (CI has no CUDA: off by
default). Writes <clone>.ci-time.json and prints a summary.
"""
import argparse
import collections
import json
import os
import re
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def launch(log, command):
    """Compiler/linker launcher: runs the command, appends its CPU seconds and
    <build folder>/<output file> to log."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    rc = subprocess.call(command)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    output = next((command[i + 1] for i in range(len(command) - 1) if command[i] == "-o"), command[-1])
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    with open(log, "a") as f:
        # The build folder (build/ or build-fuzz/) first: ninja runs the step there.
        f.write(f"{cpu:.2f} {os.path.basename(os.getcwd())}/{output}\n")
    return rc


def phase(name, command, cwd, env, logs):
    """Runs one phase; returns {name, wall, cpu, rc}. Its output goes to <logs>.<name>.log."""
    before, start = resource.getrusage(resource.RUSAGE_CHILDREN), time.time()
    with open(f"{logs}.{name}.log", "w") as out:
        rc = subprocess.call(["nice", "-n", "19", *command], cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    result = {"phase": name, "wall": round(time.time() - start, 1), "cpu": round(cpu, 1), "rc": rc}
    print(f"{name:10s} wall {result['wall']:7.1f} s   cpu {result['cpu']:7.1f} s   exit {rc}   "
          f"(load {os.getloadavg()[0]:.1f})", flush=True)
    return result


def target_of(output):
    """The CMake target of a compile step's object file (CMakeFiles/<target>.dir/...), else the output."""
    m = re.search(r"CMakeFiles/([^/]+)\.dir/", output)
    return m.group(1) if m else os.path.basename(output)


def summary(steps_log, clone):
    steps = []
    if os.path.exists(steps_log):
        for line in open(steps_log):
            cpu, output = line.split(" ", 1)
            steps.append((float(cpu), output.strip()))
    by_target = collections.Counter()
    for cpu, output in steps:
        by_target[output.split("/")[0] + " " + target_of(output)] += cpu
    costs = []
    cost_file = os.path.join(clone, "build", "Testing", "Temporary", "CTestCostData.txt")
    if os.path.exists(cost_file):
        for line in open(cost_file):
            parts = line.split()
            if len(parts) == 3:
                costs.append((float(parts[2]), parts[0]))
    return {
        "steps_cpu": round(sum(c for c, _ in steps), 1),
        "heaviest_steps": [[round(c, 2), o] for c, o in sorted(steps, reverse=True)[:25]],
        "targets_cpu": {t: round(c, 1) for t, c in by_target.most_common()},
        "tests_sum": round(sum(c for c, _ in costs), 1),
        "slowest_tests": [[round(c, 2), n] for c, n in sorted(costs, reverse=True)[:25]],
    }


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "--launch":
        sys.exit(launch(sys.argv[2], sys.argv[3:]))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rev", default="HEAD")
    ap.add_argument("--clone", required=True, help="a folder to clone into (removed first)")
    ap.add_argument("--cuda", action="store_true", help="build the CUDA backend when nvcc is found")
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    args = ap.parse_args()
    clone = os.path.abspath(args.clone)
    subprocess.check_call(["rm", "-rf", clone])
    subprocess.check_call(["git", "clone", "-q", "--no-local", ROOT, clone])
    subprocess.check_call(["git", "checkout", "-q", args.rev], cwd=clone)
    steps_log = clone + ".ci-time-steps.txt"
    if os.path.exists(steps_log):
        os.remove(steps_log)
    launcher = clone + ".ci-time-launch.sh"  # one word: CMAKE_FLAGS goes through the shell
    with open(launcher, "w") as f:
        f.write(f'#!/bin/sh\nexec {sys.executable} {os.path.abspath(__file__)} --launch {steps_log} "$@"\n')
    os.chmod(launcher, 0o755)
    flags = (f"-DKEYMESH_WERROR=ON -DCMAKE_CXX_COMPILER_LAUNCHER={launcher} -DCMAKE_CXX_LINKER_LAUNCHER={launcher}"
             + ("" if args.cuda else " -DKEYMESH_CUDA=OFF"))
    env = dict(os.environ, CI="true", CCACHE_DISABLE="1")
    jobs = f"JOBS={args.jobs}"
    rev = subprocess.check_output(["git", "log", "-1", "--format=%h %<(72,trunc)%s"], cwd=clone, text=True).strip()
    print(f"{rev}\n{args.jobs} jobs, load {os.getloadavg()[0]:.1f}", flush=True)
    phases = [
        phase("build", ["make", "build", jobs, f"CMAKE_FLAGS={flags}"], clone, env, clone),
        phase("gltf", ["make", "gltf-validator"], clone, env, clone),
        phase("ctest", ["ctest", "--output-on-failure", "-j", str(args.jobs)], os.path.join(clone, "build"), env, clone),
        phase("sanitize", ["make", "sanitize-quick", jobs, f"CMAKE_FLAGS={flags}"], clone, env, clone),
    ]
    result = {"revision": rev, "jobs": args.jobs, "phases": phases, **summary(steps_log, clone)}
    with open(clone + ".ci-time.json", "w") as f:
        json.dump(result, f, indent=1)
    print(f"compile/link steps: {result['steps_cpu']} s CPU; tests: {result['tests_sum']} s summed")
    for target, cpu in list(result["targets_cpu"].items())[:15]:
        print(f"  {target:40s} {cpu:7.1f} s CPU")
    for cost, name in result["slowest_tests"][:15]:
        print(f"  {name:60s} {cost:6.1f} s")
    sys.exit(max(p["rc"] for p in phases) and 1)


if __name__ == "__main__":
    main()
