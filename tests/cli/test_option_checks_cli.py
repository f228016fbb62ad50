"""Every checked numeric option of every command (a range, NONNEGATIVE, a
set of integers, as `keymesh <command> --help` shows it) refuses a bad
value with one short usage line naming the option and the value as typed
and what is expected, exit 2: "--smooth: -1 is out of range (0 or more)".
CLI11 2.1's own message for NONNEGATIVE printed the largest double in full
(a 309-digit number), wrote the bound 1e-9 as 0.000000, said "not in range"
of text that is no number at all, and "--scheme: x" of a set's non-integer.
The options are read from --help, so an option added later is checked too."""
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, run, tempdir  # noqa: E402

D = tempdir()
COMMANDS = ["check", "contour", "convert", "dual", "generate", "info", "labels", "pipeline", "quality", "subdivide",
            "tetrahedralize"]
# An option line of --help: "  -n,--size INT:INT in [2 - 1048576] x 3 ...".
OPTION = re.compile(r"^\s+(?:-\w,)?(--[\w-]+) (INT|FLOAT):(INT in \[(\S+) - (\S+)\]|FLOAT in \[(\S+) - (\S+)\]|"
                    r"NONNEGATIVE|\{[\d,]+\})(?: x (\d+))?")


def checked_options(command):
    """(option, kind, bounds or members, values it takes) of each checked numeric option."""
    out = []
    for line in run(command, "--help").stdout.splitlines():
        m = OPTION.match(line)
        if not m:
            continue
        name, _, check_text, ilo, ihi, flo, fhi, count = m.groups()
        kind = ("int" if ilo else "float" if flo else "nonnegative" if check_text == "NONNEGATIVE" else "set")
        out.append((name, kind, (ilo or flo, ihi or fhi) if kind in ("int", "float") else check_text,
                    int(count or 1)))
    return out


def bad_values(kind, bounds):
    """(value as typed, what the refusal says after it) for a kind of check."""
    if kind == "int":
        lo, hi = int(bounds[0]), int(bounds[1])
        return [("x", "is not an integer"), ("1.5", "is not an integer"),
                (str(lo - 1), f"is out of range ({lo} to {hi})"), (str(hi + 1), f"is out of range ({lo} to {hi})")]
    if kind == "float":
        return [("x", "is not a number"), ("nan", "is not a finite number"), ("1e999", "is not a finite number"),
                ("2", f"is out of range ({bounds[0]} to {bounds[1]})")]
    if kind == "nonnegative":
        return [("x", "is not an integer"), ("1.5", "is not an integer"), ("-1", "is out of range (0 or more)")]
    return [("x", f"not in {bounds}"), ("-1", f"not in {bounds}")]


def every_checked_option_refused_in_one_short_line():
    seen = set()
    for command in COMMANDS:
        positional = "sphere" if command == "generate" else os.path.join(D, "absent.nrrd")
        for name, kind, bounds, count in checked_options(command):
            seen.add((command, name))
            for value, said in bad_values(kind, bounds):
                p = run(command, positional, name, *[value] * count, expect=2)
                first = p.stderr.splitlines()[0]
                assert first == f"{name}: {value} {said}", (command, first)
                assert "Run with --help" in p.stderr, p.stderr
    # The options the issue named, and one of each kind, were found in --help (21 in all on 2026-11-29).
    assert len(seen) >= 21, sorted(seen)
    for option in (("labels", "--smooth"), ("labels", "--relaxation"), ("contour", "--header-bytes"),
                   ("labels", "--chunk-shape"), ("generate", "--size"), ("tetrahedralize", "--scheme"),
                   ("subdivide", "--threads")):
        assert option in seen, (option, sorted(seen))


def good_values_still_run():
    out = os.path.join(D, "g.raw")
    run("generate", "sphere", "--size", "2", "-o", out, "-q")
    assert os.path.getsize(out) == 2 * 2 * 2 * 4


check("every checked numeric option of every command: one short line naming the value and what is expected",
      every_checked_option_refused_in_one_short_line)
check("a value at the bound is still accepted (generate --size 2)", good_values_still_run)
finish()
