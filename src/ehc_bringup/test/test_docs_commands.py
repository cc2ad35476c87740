#!/usr/bin/python3
"""The commands the docs show can be pasted into a shell as they are.

Every line of a ```bash block in README.md, CHANGELOG.md, docs/*.md and src/*/*.md that is a
command (not a comment) must not use usage notation: an optional part in brackets (`[_mode:=x]`,
`[--seed N]`) or alternatives joined by `|` inside a word (`_mode:=ehc|neo_e`). Pasted, such a
line runs something else: the shell cuts `[_mode:=ehc|neo_e|tsmm]` at each `|` into a pipeline,
and the node got the argument `[_mode:=ehc`. Usage notation belongs in prose or in a tool's --help.

  /usr/bin/python3 -m pytest src/ehc_bringup/test/test_docs_commands.py
"""
import glob
import os
import re

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
OPTIONAL = re.compile(r"\[(?:_|--?)[A-Za-z]")           # [_name:=...] or [--flag ...]
ALTERNATIVES = re.compile(r"(?<![\s|])\|(?![\s|])")     # a|b inside a word (a pipe has blanks)


def doc_files(root=ROOT):
    files = [os.path.join(root, "README.md"), os.path.join(root, "CHANGELOG.md")]
    files += glob.glob(os.path.join(root, "docs", "*.md")) + glob.glob(os.path.join(root, "src", "*", "*.md"))
    return sorted(f for f in files if os.path.exists(f))


def bash_lines(text):
    """(line number, line) of every command line inside ```bash blocks."""
    out, inside = [], False
    for n, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("```"):
            inside = not inside and stripped in ("```bash", "```sh", "```shell", "```console")
            continue
        if inside and stripped and not stripped.startswith("#"):
            out.append((n, line))
    return out


def problems(text):
    bad = []
    for n, line in bash_lines(text):
        code = re.sub(r"'[^']*'|\"[^\"]*\"", "''", line)  # quoted text is data, not notation
        code = code.split(" #", 1)[0]
        if OPTIONAL.search(code) or ALTERNATIVES.search(code):
            bad.append((n, line.strip()))
    return bad


def test_the_checker_finds_usage_notation_and_passes_real_commands():
    doc = "\n".join([
        "```bash",
        "rosrun ehc_control ehc_controller_node _config:=c.yaml [_mode:=ehc|neo_e|tsmm]",
        "rosrun ehc_bringup ehc_experiment reach --robot r [--seed 1]",
        "rosrun ehc_control ehc_controller_node _config:=c.yaml _mode:=ehc|tsmm",
        "rosparam list | grep ehc   # a real pipe",
        "rostopic pub /x ehc_msgs/X \"{names: [joint1, joint2], velocities: [0.05, 0]}\"",
        "[ -f devel/setup.bash ] && source devel/setup.bash",
        "```",
        "prose with [_mode:=ehc|tsmm] is fine",
    ])
    assert [n for n, _ in problems(doc)] == [2, 3, 4]


def test_every_command_in_the_docs_is_pasteable():
    found = []
    for path in doc_files():
        with open(path) as f:
            for n, line in problems(f.read()):
                found.append("%s:%d: %s" % (os.path.relpath(path, ROOT), n, line))
    assert doc_files(), "no docs found"
    assert not found, "usage notation in commands (not pasteable):\n" + "\n".join(found)
