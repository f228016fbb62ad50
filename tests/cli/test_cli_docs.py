"""The documents stay true to the binary and to each other: every
docs/cli/<command>.md holds exactly `keymesh <command> --help` between its
markers (scripts/cli_docs.py --check), the check fails on a page that drifted,
lost its markers or names a command that is gone, a rewrite restores the block
and keeps the hand-written notes, and every relative link in README.md,
python/README.md and docs/**/*.md names a file that exists.

    python3 tests/cli/test_cli_docs.py build/keymesh
"""
import glob
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, SOURCE_DIR, check, finish, tempdir  # noqa: E402

SCRIPT = os.path.join(SOURCE_DIR, "scripts", "cli_docs.py")
PAGES = os.path.join(SOURCE_DIR, "docs", "cli")
D = tempdir()


def cli_docs(*args):
    return subprocess.run([sys.executable, SCRIPT, "--keymesh", KEYMESH, *args],
                          capture_output=True, text=True, timeout=300)


def copy_of_pages(name):
    folder = os.path.join(D, name)
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(PAGES, folder)
    return folder


def the_pages_hold_the_binarys_help():
    p = cli_docs("--check")
    assert p.returncode == 0, "docs/cli is not the binary's --help; run python3 scripts/cli_docs.py\n" + p.stdout + p.stderr


def every_command_has_a_page_with_its_usage():
    top = subprocess.run([KEYMESH, "--help"], capture_output=True, text=True, timeout=60).stdout
    names = re.findall(r"^  (\S+)\s", top.split("\nSubcommands:\n", 1)[1], flags=re.M)
    assert len(names) >= 10, names
    for name in names:
        page = open(os.path.join(PAGES, f"{name}.md")).read()
        assert f"Usage: keymesh {name} [OPTIONS]" in page, name


def expect_check_fails(folder, *phrases):
    p = cli_docs("--check", "--pages", folder)
    assert p.returncode == 1, p.stdout + p.stderr
    for phrase in phrases:
        assert phrase in p.stdout, (phrase, p.stdout)


def a_drifted_block_fails_and_a_rewrite_mends_it():
    folder = copy_of_pages("drift")
    page = os.path.join(folder, "contour.md")
    text = open(page).read()
    notes = "\n\nA hand-written note that the rewrite must keep.\n"
    drifted = text.replace("--iso FLOAT", "--isovalue FLOAT", 1) + notes
    assert drifted != text + notes
    open(page, "w").write(drifted)
    expect_check_fails(folder, "contour.md: its `keymesh contour --help` block differs")
    p = cli_docs("--pages", folder)
    assert p.returncode == 0, p.stdout + p.stderr
    assert open(page).read() == text + notes
    assert cli_docs("--check", "--pages", folder).returncode == 0


def a_missing_page_or_marker_or_stray_page_fails():
    folder = copy_of_pages("missing")
    os.remove(os.path.join(folder, "dual.md"))
    expect_check_fails(folder, "dual.md: missing")
    folder = copy_of_pages("markers")
    page = os.path.join(folder, "info.md")
    open(page, "w").write(open(page).read().replace("<!-- END", "<!-- FIN"))
    expect_check_fails(folder, "info.md: no single pair of `keymesh info --help` markers")
    folder = copy_of_pages("stray")
    open(os.path.join(folder, "explode.md"), "w").write("# `keymesh explode`\n")
    expect_check_fails(folder, "explode.md: no such subcommand")


LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def documents():
    paths = [os.path.join(SOURCE_DIR, "README.md"), os.path.join(SOURCE_DIR, "python", "README.md")]
    paths += glob.glob(os.path.join(SOURCE_DIR, "docs", "**", "*.md"), recursive=True)
    return [p for p in paths if os.path.exists(p)]


def broken_links(path):
    text = re.sub(r"```.*?```", "", open(path).read(), flags=re.S)  # code blocks hold no links
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue  # a URL or an anchor in the same page
        file = target.split("#", 1)[0]
        if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(path), file))):
            broken.append(target)
    return broken


def every_relative_link_resolves():
    docs = documents()
    assert len(docs) >= 15, docs
    broken = {os.path.relpath(p, SOURCE_DIR): b for p in docs if (b := broken_links(p))}
    assert not broken, broken


def the_link_check_sees_a_broken_link():
    page = os.path.join(D, "page.md")
    open(page, "w").write("[there](page.md) [gone](no/such/file.md) ![pic](nothere.png) [web](https://x.org)\n"
                          "```\n[in code](ignored.md)\n```\n")
    assert broken_links(page) == ["no/such/file.md", "nothere.png"], broken_links(page)


check("docs/cli holds every command's --help as the binary prints it", the_pages_hold_the_binarys_help)
check("every subcommand has a page with its usage line", every_command_has_a_page_with_its_usage)
check("a drifted block fails the check; a rewrite mends it and keeps the notes",
      a_drifted_block_fails_and_a_rewrite_mends_it)
check("a missing page, a lost marker or a page of no command fails the check", a_missing_page_or_marker_or_stray_page_fails)
check("the link check finds a broken link and skips URLs and code", the_link_check_sees_a_broken_link)
check("every relative link in README.md, python/README.md and docs/ resolves", every_relative_link_resolves)
shutil.rmtree(D, ignore_errors=True)
finish()
