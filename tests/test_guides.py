"""The guides' commands run, and print what the guides show.

A guide shows a command and its output in a ```console block:

    ```console
    $ deburr-drake simulate --duration 3 --out out/first
    pre-flight: the sampled loop at the start pose is stable, rho = ... (... s)
    ...
    stopped at t = 3.000 s: duration
    ```

Every ``$ `` line is a command; the lines under it, up to the next ``$ ``
line or the end of the block, are what it prints on stdout (stderr is not
compared: Drake's and the package's warnings go there; a command that
shows them redirects them itself, ``2>&1``). Two placeholders stand for
what varies from run to run or from machine to machine:

- ``...`` inside a line stands for any text on that line (wall times,
  timings);
- a line that is only ``...`` stands for any number of lines, none
  included (the lines a guide leaves out).

Everything else must match exactly, trailing blanks aside: the simulation
is deterministic, so a metric a guide shows is what the command prints.
The commands of a page run in order in one fresh directory (a later
command may read what an earlier one wrote), with ``deburr-drake`` and
``python`` this interpreter's (``python -m deburr_drake.cli``); the
repository's ``scripts``, ``examples`` and ``studies`` are linked into it.

A file a command reads is shown in a code block captioned with its name,
which the tests write into that directory before the commands below it
run:

    ```{code-block} yaml
    :caption: my_part.yaml

    base: pocket
    ```

A command too long for the tests (a full pass, a sweep) is shown in a
```sh block instead, which is not run; the guide says it is shown, not
run. The guides keep their console commands to a few simulated seconds.
"""

import os
from pathlib import Path
import re
import shlex
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

#: The guides a user follows: each at most MAX_LINES lines.
GUIDES = [
    "getting-started.md",
    "python-api.md",
    "localisation.md",
    "own-part.md",
    "own-robot.md",
    "stability.md",
    "job.md",
]
MAX_LINES = 250


def console_blocks(text):
    """The ```console blocks of a Markdown page, in order."""
    return re.findall(r"^```console\n(.*?)^```", text, re.S | re.M)


def page_steps(text):
    """[("run", console block) or ("write", file name, text)] of a page,
    in order: its console blocks and its code blocks captioned with a file
    name."""
    steps = []
    blocks = r"^```(console|\{code-block\}[^\n]*)\n(.*?)^```"
    for kind, body in re.findall(blocks, text, re.S | re.M):
        if kind == "console":
            steps.append(("run", body))
            continue
        options = re.match(r"((?::\w+:[^\n]*\n)*)\n?", body)
        name = re.search(r"^:caption: ([\w.-]+\.\w+)$", options[1], re.M)
        if name:
            steps.append(("write", name[1], body[options.end() :]))
    return steps


def commands(block):
    """[(command, expected lines)] of a console block."""
    out = []
    for line in block.splitlines():
        if line.startswith("$ "):
            out.append((line[2:], []))
        elif out:
            out[-1][1].append(line.rstrip())
        else:
            raise ValueError(f"output before any command: {line!r}")
    return out


def expected_pattern(lines):
    """A regex matching the output ``lines`` show (the placeholders
    above)."""
    parts = []
    for line in lines:
        if line.strip() == "...":
            parts.append(r"(?:[^\n]*\n)*?")
        else:
            pieces = [re.escape(p) for p in line.split("...")]
            parts.append("[^\n]*".join(pieces) + r"\n")
    return "".join(parts)


def matches(expected, printed):
    """Whether ``printed`` (text) is what the ``expected`` lines show."""
    text = "".join(line.rstrip() + "\n" for line in printed.splitlines())
    return re.fullmatch(expected_pattern(expected), text) is not None


def _shell_command(command):
    """The guide's command with this interpreter's deburr-drake and
    python."""
    words = shlex.split(command)
    python = shlex.quote(sys.executable)
    if words[0] == "deburr-drake":
        return f"{python} -m deburr_drake.cli" + command[len("deburr-drake") :]
    if words[0] in ("python", "python3"):
        return python + command[len(words[0]) :]
    return command


def pages_with_console():
    return [
        p
        for p in [ROOT / "README.md"] + sorted(DOCS.glob("*.md"))
        if console_blocks(p.read_text())
    ]


def test_the_placeholders():
    shown = ["a ... b", "...", "end"]
    assert matches(shown, "a 1.0 s b\nend\n")
    assert matches(shown, "a  b\nx\ny\nend")
    assert not matches(shown, "a b\nend\n")  # "a ... b" keeps its blanks
    assert not matches(shown, "a 1 b\nend\nmore\n")
    assert not matches(["x 1"], "x 2\n")


def test_a_captioned_code_block_is_a_file_the_commands_read():
    page = (
        "```{code-block} yaml\n:caption: a.yaml\n\nbase: pocket\n```\n"
        "```{code-block} yaml\n:caption: not a file\n\nx: 1\n```\n"
        "```console\n$ cat a.yaml\nbase: pocket\n```\n"
    )
    assert page_steps(page) == [
        ("write", "a.yaml", "base: pocket\n"),
        ("run", "$ cat a.yaml\nbase: pocket\n"),
    ]


def test_every_guide_is_short_and_shows_commands_that_run():
    for name in GUIDES:
        text = (DOCS / name).read_text()
        assert len(text.splitlines()) <= MAX_LINES, name
        assert not re.search(r"\bissue \d+|\bcommit [0-9a-f]{7}", text), name
    runnable = {p.name for p in pages_with_console()}
    assert set(GUIDES) - {"python-api.md"} <= runnable


@pytest.mark.slow
@pytest.mark.parametrize("page", pages_with_console(), ids=lambda p: p.name)
def test_console_output_is_what_the_command_prints(page, tmp_path):
    for name in ("scripts", "examples", "studies"):
        (tmp_path / name).symlink_to(ROOT / name)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for step in page_steps(page.read_text()):
        if step[0] == "write":
            (tmp_path / step[1]).write_text(step[2])
            continue
        for command, expected in commands(step[1]):
            result = subprocess.run(
                _shell_command(command),
                shell=True,
                cwd=tmp_path,
                capture_output=True,
                text=True,
                timeout=600,
                env=env,
            )
            assert matches(expected, result.stdout), (
                f"{page.name}: `{command}` printed\n{result.stdout}\n"
                f"(stderr: {result.stderr[-2000:]})\nthe page shows\n"
                + "\n".join(expected)
            )
