"""Every shell and Python example of README.md runs as written (issue 18).

The examples run in README order, in one fresh temporary folder laid out like
the repository (``.venv``, ``examples`` and ``benchmarks`` are links to the
real ones, ``../shared`` to the shared data), so each file an example uses
must have been made by an earlier example. Python blocks share one namespace,
as in one interpreter session; shell blocks run in ``bash -e``.

A block may be preceded by an HTML comment, invisible on the rendered page:

* ``<!-- readme-test: skip (why) -->``: not run (``make demo``/``make test``:
  the whole demo and the whole suite, run on their own);
* ``<!-- readme-test: file NAME -->``: the block's text is a file the user
  saves as NAME;
* ``<!-- readme-test: list GLOB (why) -->``: commands that are measurements
  (``make bench``); the test checks that they name exactly the files of GLOB.

Long runs are shortened by the substitutions of :data:`QUICK` (shorter
simulations, fewer optimiser iterations), each of which must match the
README, so what the README shows is what a user types.

Why a parser of our own rather than pytest-examples or sybil: the README is
one story, shell and Python interleaved, each step reading the files of the
ones before. pytest-examples runs Python blocks one by one and has no shell;
sybil would need a custom shell parser and a new dependency, and neither
shortens the long runs. Sixty lines here do all three.
"""

from __future__ import annotations

import os
import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
SHARED = ROOT.parent / "shared"
UR10_DATA = SHARED / "data" / "ur10-ext_observer"

QUICK: tuple[tuple[str, str, int], ...] = (
    # (README text, what the test runs instead, how many times it occurs)
    (
        'load_scenario("puma560-thesis").run(seed=1)',
        'load_scenario("puma560-thesis").with_duration(3.0).run(seed=1)',
        1,
    ),
    ('load_scenario("panda-gaz").run(', 'load_scenario("panda-gaz").with_duration(4.0).run(', 2),
    ("simulate panda-gaz -o", "simulate panda-gaz --duration 4 -o", 3),
    (
        "--harmonics 5 --frequency 0.1",
        "--harmonics 2 --frequency 0.1 --restarts 1 --iterations 5",
        1,
    ),
    ("duration=60.0)", "duration=3.0)", 1),
)

_BLOCK = re.compile(
    r"(?:<!-- readme-test: (?P<directive>[^\n]*?) -->\n)?```(?P<lang>\w+)\n(?P<body>.*?)```",
    re.DOTALL,
)


@dataclass(frozen=True)
class Block:
    """One fenced block of the README: language, text, directive, line number."""

    lang: str
    body: str
    directive: str
    line: int


def readme_blocks() -> list[Block]:
    """The fenced blocks of README.md, in order."""
    text = README.read_text(encoding="utf-8")
    return [
        Block(m["lang"], m["body"], m["directive"] or "", text.count("\n", 0, m.start("lang")) + 1)
        for m in _BLOCK.finditer(text)
    ]


def _quick(text: str) -> str:
    for old, new, _ in QUICK:
        text = text.replace(old, new)
    return text


def _folder(tmp_path: Path) -> Path:
    """A fresh folder that looks like the repository to the README's relative paths."""
    work = tmp_path / "main"
    work.mkdir()
    for name in (".venv", "examples", "benchmarks"):
        (work / name).symlink_to(ROOT / name)
    if SHARED.is_dir():
        (tmp_path / "shared").symlink_to(SHARED)
    return work


def _run_shell(block: Block, cwd: Path) -> None:
    env = {**os.environ, "COLUMNS": "200", "NO_COLOR": "1"}
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", _quick(block.body)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, (
        f"README.md line {block.line}: exit code {done.returncode}\n"
        f"--- stdout\n{done.stdout[-4000:]}\n--- stderr\n{done.stderr[-4000:]}"
    )


def test_quick_substitutions_match_the_readme() -> None:
    """Each shortening of :data:`QUICK` applies where the README says it does."""
    runnable = "".join(b.body for b in readme_blocks() if not b.directive.startswith("skip"))
    for old, _, count in QUICK:
        assert runnable.count(old) == count, old


def test_readme_lists_every_benchmark() -> None:
    """The benchmark commands name exactly the scripts ``make bench`` runs, and the count."""
    (block,) = [b for b in readme_blocks() if b.directive.startswith("list ")]
    pattern = block.directive.split()[1]
    listed = sorted(re.findall(r"benchmarks/bench_\w+\.py", block.body))
    assert listed == sorted(str(p.relative_to(ROOT)) for p in ROOT.glob(pattern))
    words = {
        7: "seven",
        8: "eight",
        9: "nine",
        10: "ten",
        11: "eleven",
        12: "twelve",
        13: "thirteen",
        14: "fourteen",
    }
    assert f"the {words[len(listed)]} scripts below" in README.read_text(encoding="utf-8")


def test_readme_examples_run_in_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every shell and Python example runs, in order, in one fresh folder."""
    work = _folder(tmp_path)
    monkeypatch.chdir(work)
    namespace: dict[str, object] = {"__name__": "__readme__"}
    ran = []
    for block in readme_blocks():
        if block.directive.startswith(("skip", "list ")):
            continue
        if block.directive.startswith("file "):
            (work / block.directive.split()[1]).write_text(block.body, encoding="utf-8")
            continue
        if "ur10" in block.body and not UR10_DATA.is_dir():
            continue  # the real recordings are not part of the repository
        if block.lang == "python":
            code = compile(_quick(block.body), f"README.md:{block.line}", "exec")
            exec(code, namespace)
        elif block.lang == "bash":
            _run_shell(block, work)
        else:
            pytest.fail(f"README.md line {block.line}: a {block.lang} block without a directive")
        ran.append(block.line)
    made = {p.name for p in work.iterdir()}
    expected = {"run.parquet", "tv.yaml", "friction.html", "inertial.yaml", "panda-excitation.yaml"}
    assert expected <= made, sorted(made)
    assert len(ran) >= 8, ran
