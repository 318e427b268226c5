"""The README's examples run, and print what the README says they print.

Each ``console`` block's ``$ railcontact ...`` lines are run and their output compared with
the lines under them; each ``python`` block is run and, when a ``text`` block follows it,
its output is compared with that block. The comparison is doctest's with ``ELLIPSIS``
(``...`` stands for anything: wall times, paths) and ``NORMALIZE_WHITESPACE``. The FMU
example runs on an FMU built into a temporary folder, not the repository's ``dist/``.
"""

from __future__ import annotations

import doctest
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
FMU_PATH = "dist/RailContact.fmu"  # as the README writes it


@dataclass(frozen=True)
class Block:
    """A fenced block of the README: its info string, text and first line number."""

    lang: str
    text: str
    line: int


def blocks(text: str) -> list[Block]:
    """The README's fenced code blocks, in order."""
    out, lang, body, start = [], None, [], 0
    for number, line in enumerate(text.splitlines(), 1):
        fence = re.match(r"^```(\S*)\s*$", line)
        if fence and lang is None:
            lang, body, start = fence.group(1), [], number + 1
        elif fence:
            out.append(Block(lang, "\n".join(body) + "\n", start))
            lang = None
        elif lang is not None:
            body.append(line)
    assert lang is None, "an unclosed fence in the README"
    return out


def same_output(want: str, got: str) -> bool:
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    return doctest.OutputChecker().check_output(want, got, flags)


def run(args: list[str], **kw) -> str:
    res = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=900, **kw)
    assert res.returncode == 0, f"{args} failed ({res.returncode}):\n{res.stdout}{res.stderr}"
    return res.stdout


README_BLOCKS = blocks(README.read_text(encoding="utf-8"))
PYTHON = [(i, b) for i, b in enumerate(README_BLOCKS) if b.lang == "python"]
CONSOLE = [b for b in README_BLOCKS if b.lang == "console"]


def expected_after(index: int) -> str | None:
    """The ``text`` block right after block ``index``, or None."""
    nxt = README_BLOCKS[index + 1] if index + 1 < len(README_BLOCKS) else None
    return nxt.text if nxt is not None and nxt.lang == "text" else None


def test_readme_is_short_and_names_the_test_command():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    fresh = (ROOT / ".ci" / "fresh_clone_test").read_text(encoding="utf-8")
    command = next(line for b in README_BLOCKS if b.lang == "bash"
                   for line in b.text.splitlines() if "pytest" in line)
    assert ".ci/fresh_clone_test" in ci and "sphinx-build -W" in ci
    assert command.strip() in fresh, "CI must run the README's test command"


def test_readme_has_its_examples():
    assert len(PYTHON) >= 2 and len(CONSOLE) >= 2
    assert all(expected_after(i) is not None for i, _ in PYTHON), "each example shows its output"


@pytest.fixture(scope="module")
def fmu(tmp_path_factory) -> Path:
    from railcontact.fmu.build import build_fmu

    return build_fmu(tmp_path_factory.mktemp("readme") / "RailContact.fmu")


def _commands(block: Block):
    """(command, expected output) pairs of a console block."""
    items, command, lines = [], None, []
    for line in block.text.splitlines():
        if line.startswith("$ "):
            if command is not None:
                items.append((command, "\n".join(lines) + "\n"))
            command, lines = line[2:], []
        else:
            lines.append(line)
    if command is not None:
        items.append((command, "\n".join(lines) + "\n"))
    return items


@pytest.mark.parametrize("block", CONSOLE, ids=lambda b: f"line{b.line}")
def test_console_example(block, tmp_path):
    for command, want in _commands(block):
        args = command.split()
        assert args[0] == "railcontact", command
        if args[1:3] == ["fmu", "build"]:
            out = tmp_path / "RailContact.fmu"
            args = [a if a != FMU_PATH else str(out) for a in args]
            want = want.replace(FMU_PATH, str(out))
        got = run([sys.executable, "-m", "railcontact", *args[1:]])
        assert same_output(want, got), f"README line {block.line}: `{command}` printed\n{got}"


@pytest.mark.parametrize("index, block", PYTHON, ids=[f"line{b.line}" for _, b in PYTHON])
def test_python_example(index, block, request):
    code = block.text
    if FMU_PATH in code:
        code = code.replace(FMU_PATH, str(request.getfixturevalue("fmu")))
    got = run([sys.executable, "-c", code])
    want = expected_after(index)
    assert same_output(want, got), f"README line {block.line} printed\n{got}\nnot\n{want}"
