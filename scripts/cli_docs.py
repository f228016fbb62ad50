#!/usr/bin/env python3
"""Writes each command's `keymesh <command> --help` into docs/cli/<command>.md,
and `keymesh --help` into docs/cli/README.md, between two marker lines, so
the pages cannot drift from the binary: the hand-written notes around the
block stay as they are. A command with no page yet gets one (a title and the
block); a page whose command is gone is reported, not deleted.

    python3 scripts/cli_docs.py [--keymesh build/keymesh]          # rewrite the blocks
    python3 scripts/cli_docs.py [--keymesh build/keymesh] --check  # exit 1 if any page differs

The help is taken on one CPU (the --threads bound, 4 x the processors, at
least 64, is then the same on every machine), and the usage line names the
command `keymesh`, whatever path ran it. tests/cli/test_cli_docs.py runs
--check.
"""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = os.path.join(ROOT, "docs", "cli")


def begin_marker(command):
    return f"<!-- BEGIN `{command} --help`: written by scripts/cli_docs.py from the binary; do not edit -->"


def end_marker(command):
    return f"<!-- END `{command} --help` -->"


def one_cpu():
    # omp_get_num_procs() counts the CPUs this process may run on.
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def help_text(keymesh, *subcommand):
    p = subprocess.run([keymesh, *subcommand, "--help"], capture_output=True, text=True, timeout=60,
                       stdin=subprocess.DEVNULL, preexec_fn=one_cpu)
    if p.returncode != 0:
        sys.exit(f"cli_docs.py: {keymesh} {' '.join(subcommand)} --help: exit {p.returncode}: {p.stderr.strip()}")
    text = re.sub(r"^Usage: \S+", "Usage: keymesh", p.stdout, count=1, flags=re.M)
    return "\n".join(line.rstrip() for line in text.rstrip().splitlines())


def subcommands(top_help):
    """The names listed under "Subcommands:" in `keymesh --help`."""
    section = top_help.split("\nSubcommands:\n", 1)
    if len(section) != 2:
        sys.exit("cli_docs.py: `keymesh --help` lists no subcommands")
    return [m.group(1) for m in re.finditer(r"^  (\S+)\s", section[1], flags=re.M)]


def block(command, text):
    return f"{begin_marker(command)}\n```text\n{text}\n```\n{end_marker(command)}"


def new_page(command, text):
    title = f"# `{command}`" if command != "keymesh" else "# The `keymesh` command"
    return f"{title}\n\n{block(command, text)}\n"


def with_block(page, command, text):
    """The page with its help block replaced; None when its markers are missing."""
    begin, end = begin_marker(command), end_marker(command)
    if page.count(begin) != 1 or page.count(end) != 1 or page.index(begin) > page.index(end):
        return None
    head, rest = page.split(begin, 1)
    return head + block(command, text) + rest.split(end, 1)[1]


def expected_pages(keymesh, folder):
    """{path: (command, help text)} for the index page and every subcommand's."""
    top = help_text(keymesh)
    pages = {os.path.join(folder, "README.md"): ("keymesh", top)}
    for name in subcommands(top):
        pages[os.path.join(folder, f"{name}.md")] = (f"keymesh {name}", help_text(keymesh, name))
    return pages


def differences(keymesh, folder=PAGES):
    """One line for every page that is missing, lacks its markers or holds another --help."""
    problems = []
    pages = expected_pages(keymesh, folder)
    for path, (command, text) in pages.items():
        rel = os.path.relpath(path, ROOT)
        if not os.path.exists(path):
            problems.append(f"{rel}: missing (`{command} --help` has no page)")
            continue
        page = open(path).read()
        rewritten = with_block(page, command, text)
        if rewritten is None:
            problems.append(f"{rel}: no single pair of `{command} --help` markers")
        elif rewritten != page:
            problems.append(f"{rel}: its `{command} --help` block differs from the binary's")
    for name in sorted(os.listdir(folder)):
        if name.endswith(".md") and os.path.join(folder, name) not in pages:
            problems.append(f"{os.path.relpath(os.path.join(folder, name), ROOT)}: no such subcommand in `keymesh --help`")
    return problems


def rewrite(keymesh, folder=PAGES):
    os.makedirs(folder, exist_ok=True)
    for path, (command, text) in expected_pages(keymesh, folder).items():
        old = open(path).read() if os.path.exists(path) else None
        new = new_page(command, text) if old is None else with_block(old, command, text)
        if new is None:
            sys.exit(f"cli_docs.py: {os.path.relpath(path, ROOT)}: no single pair of `{command} --help` markers")
        if new != old:
            with open(path + ".tmp", "w") as f:
                f.write(new)
            os.replace(path + ".tmp", path)
            print(f"wrote {os.path.relpath(path, ROOT)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--keymesh", default=os.path.join(ROOT, "build", "keymesh"), help="the binary (default build/keymesh)")
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 when a page differs from the binary")
    ap.add_argument("--pages", default=PAGES, help="the pages' folder (default docs/cli)")
    a = ap.parse_args()
    if a.check:
        problems = differences(a.keymesh, a.pages)
        for line in problems:
            print(line)
        if problems:
            print("run: python3 scripts/cli_docs.py --keymesh", a.keymesh)
        sys.exit(1 if problems else 0)
    rewrite(a.keymesh, a.pages)
    for line in differences(a.keymesh, a.pages):  # pages of commands that are gone
        print(line)


if __name__ == "__main__":
    main()
