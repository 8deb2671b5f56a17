"""Every shell block of README.md and docs/*.md runs, so that no page can rot.

A block fenced ```sh or ```bash runs with bash (``set -euo pipefail``) as if from the
repository root: in a scratch folder that links every top-level entry of the repository
(``target/``, ``models/``, ``scripts/``, ...) and, beside it, ``../shared/data`` linked to the
shared data (``$MVGRASP_SHARED_DATA``, as conftest.py finds it). What a block writes lands in the
scratch folder, never in the repository: an ``--out`` into a linked entry is refused. Each
block runs on its own (a block that plans on a rendered folder renders it first), and a block
that names ``../shared/data`` skips, like every test here, when that data is absent.

``cargo run --release --bin NAME --`` becomes ``target/dist/NAME``, ``cargo run --release
--example NAME --`` becomes ``target/dist/examples/NAME``, and a path into ``target/release/``
one into ``target/dist/``. The ``dist`` profile is the release profile without debug info, and
scripts/test.sh's ``cargo test --profile dist`` has built every binary and example into
target/dist/ before this test runs (by hand: ``cargo build --profile dist --bins --examples``).
The docs run no other cargo command.

Blocks fenced ```sh slow (the full evaluations and benchmarks, minutes to hours) and the
README's first block (the default ``plan`` run, and the test command, which would recurse) are
checked, not run: each command's program must exist, and every ``--flag`` it uses must appear
in its ``--help`` output (a binary or example) or in its source (a Python module or script; a
shell script or the files beside it, to which it may pass its arguments). A block that runs
must take under ``FAST_BLOCK_S``; a longer one belongs in ```sh slow. Install and cluster
commands are fenced ```text and are not run.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from conftest import REPO_ROOT, shared_data

FAST_BLOCK_S = 60.0
FENCE = re.compile(r"^```(sh|bash)([^\n]*)\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)
CARGO_BIN = re.compile(r"cargo run --release --bin (\w+)(?: --(?=\s|$))?")
CARGO_EXAMPLE = re.compile(r"cargo run --release --example (\w+)(?: --(?=\s|$))?")
SHARED = "../shared/data"
BUILD = "cargo build --profile dist --bins --examples"
ONLY_CARGO_RUN = "the docs run cargo only as `cargo run --release --bin/--example NAME`"


def pages() -> list[Path]:
    return [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    slow: bool
    text: str

    @property
    def name(self) -> str:
        return f"{self.page.relative_to(REPO_ROOT)}:{self.line}"


def blocks() -> list[Block]:
    found = []
    for page in pages():
        text = page.read_text()
        for number, match in enumerate(FENCE.finditer(text)):
            line = text.count("\n", 0, match.start()) + 1
            # The README's first block: `plan`'s default run and the test command (recursion).
            slow = "slow" in match.group(2).split() or (page.name == "README.md" and number == 0)
            found.append(Block(page, line, slow, match.group(3)))
    return found


def rewritten(text: str) -> str:
    """The block with its cargo runs replaced by the binaries the tests built."""
    text = CARGO_BIN.sub(r"target/dist/\1", text)
    text = CARGO_EXAMPLE.sub(r"target/dist/examples/\1", text)
    return re.sub(r"(?<![\w/])target/release/", "target/dist/", text)


def commands(text: str) -> list[list[str]]:
    """The block's commands as words (continuations joined, comments and blanks dropped)."""
    joined = re.sub(r"\\\n", " ", text)
    words = [shlex.split(line, comments=True) for line in joined.splitlines()]
    return [w for w in words if w]


def shared_paths(text: str) -> list[str]:
    """The shared-data paths a block names, relative to the shared data folder."""
    found = re.findall(rf"{re.escape(SHARED)}(?:/(\S*))?", text)
    return sorted({m.split("*")[0].rstrip("/") for m in found})


def check_outputs_stay_in_scratch(block: Block) -> None:
    entries = {p.name for p in REPO_ROOT.iterdir()}
    for value in re.findall(r"--out[ =](\S+)", block.text):
        first = Path(value).parts[0]
        assert first not in entries, f"{block.name}: --out {value} writes into the repository"


def scratch_root(tmp_path: Path) -> Path:
    """A folder that looks like the repository root, with ../shared/data beside it."""
    root = tmp_path / "repo"
    root.mkdir()
    for entry in REPO_ROOT.iterdir():
        if entry.name != ".git":
            os.symlink(entry, root / entry.name)
    data = Path(os.environ.get("MVGRASP_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))
    if data.exists():
        (tmp_path / "shared").mkdir()
        os.symlink(data.resolve(), tmp_path / "shared" / "data")
    return root


def environment(tmp_path: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    env.setdefault("XDG_RUNTIME_DIR", str(tmp_path))
    return env


HELP: dict[str, str] = {}


def help_text(program: Path) -> str:
    if str(program) not in HELP:
        run = subprocess.run([program, "--help"], check=False, capture_output=True, text=True)
        assert run.returncode == 0, f"{program} --help: {run.stderr}"
        HELP[str(program)] = run.stdout
    return HELP[str(program)]


def python_source(words: list[str]) -> tuple[Path, list[str]]:
    """The source file of `python -m MODULE ...` or `python FILE ...`, and the rest."""
    if words[0] == "-m":
        parts = words[1].split(".")
        for root in (REPO_ROOT / "training", REPO_ROOT / "py" / "python", REPO_ROOT):
            module = root.joinpath(*parts)
            for source in (module.with_suffix(".py"), module / "__main__.py"):
                if source.is_file():
                    return source, words[2:]
        pytest.fail(f"python -m {words[1]}: no such module in the repository")
    return REPO_ROOT / words[0], words[1:]


def check_command(block: Block, words: list[str]) -> None:
    """The program exists and knows every flag the command gives it."""
    while words and re.fullmatch(r"\w+=\S*", words[0]):  # VAR=value before the program
        words = words[1:]
    program, rest = words[0], words[1:]
    where = f"{block.name}: {shlex.join(words)}"
    assert program != "cargo", f"{where}: {ONLY_CARGO_RUN}"
    if program.startswith("target/dist/"):
        binary = REPO_ROOT / program
        assert binary.is_file(), f"{where}: no {binary} (build: {BUILD})"
        known = help_text(binary)
    elif program in ("python", "python3"):
        source, rest = python_source(rest)
        assert source.is_file(), f"{where}: no {source}"
        known = source.read_text()
    else:
        script = REPO_ROOT / program
        assert "/" in program and script.is_file() and os.access(script, os.X_OK), (
            f"{where}: {program} is not a program of the repository (fence installs as ```text)"
        )
        # A script may pass its flags on to the files beside it (benches/lsm/run.sh to bench.py).
        known = "\n".join(f.read_text() for f in script.parent.iterdir() if f.is_file())
    for flag in (w.split("=")[0] for w in rest if w.startswith("--") and len(w) > 2):
        assert re.search(rf"(?<![\w-]){re.escape(flag)}(?![\w-])", known), (
            f"{where}: {program} does not know {flag}"
        )


BLOCKS = blocks()


def test_the_docs_have_blocks_to_run() -> None:
    assert any(b.page.name == "README.md" and not b.slow for b in BLOCKS)
    assert len({b.page for b in BLOCKS}) >= 5


@pytest.mark.parametrize("block", BLOCKS, ids=[b.name for b in BLOCKS])
def test_a_shell_block(block: Block, tmp_path: Path) -> None:
    check_outputs_stay_in_scratch(block)
    if block.slow:
        for words in commands(rewritten(block.text)):
            check_command(block, words)
        return
    for relative in shared_paths(block.text):
        shared_data(relative)
    text = rewritten(block.text)
    other_cargo = re.search(r"(^|[;&|(]) *cargo ", text, flags=re.MULTILINE)
    assert not other_cargo, f"{block.name}: {ONLY_CARGO_RUN}"
    started = time.monotonic()
    run = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", text],
        cwd=scratch_root(tmp_path), env=environment(tmp_path), check=False,
        capture_output=True, text=True, timeout=4 * FAST_BLOCK_S,
    )  # fmt: skip
    seconds = time.monotonic() - started
    output = f"{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    assert run.returncode == 0, f"{block.name} failed:\n{text}\n{output}"
    assert seconds < FAST_BLOCK_S, f"{block.name} took {seconds:.0f} s: fence it ```sh slow"


LINK = re.compile(r"\]\(([^)\s]+)\)")


def slug(heading: str) -> str:
    """GitHub's anchor of a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower().replace("`", ""))
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = re.sub(r"^```.*?^```", "", page.read_text(), flags=re.MULTILINE | re.DOTALL)
    return {slug(h) for h in re.findall(r"^#+ (.*)$", text, flags=re.MULTILINE)}


def links(page: Path) -> list[tuple[Path, str]]:
    text = re.sub(r"^```.*?^```", "", page.read_text(), flags=re.MULTILINE | re.DOTALL)
    found = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # https:, mailto:
        path, _, anchor = target.partition("#")
        found.append(((page.parent / path).resolve() if path else page, anchor))
    return found


LINKED = [*pages(), REPO_ROOT / "CHANGELOG.md", REPO_ROOT / "models" / "README.md"]


@pytest.mark.parametrize("page", LINKED, ids=[str(p.relative_to(REPO_ROOT)) for p in LINKED])
def test_the_links_of_a_page_resolve(page: Path) -> None:
    for target, anchor in links(page):
        assert target.exists(), f"{page.name}: a link to {target}, which does not exist"
        if anchor and target.suffix == ".md":
            assert anchor in anchors(target), f"{page.name}: no heading #{anchor} in {target.name}"


def test_every_docs_page_is_reachable_from_the_readme() -> None:
    seen, todo = set(), [REPO_ROOT / "README.md"]
    while todo:
        page = todo.pop()
        if page in seen:
            continue
        seen.add(page)
        todo += [t for t, _ in links(page) if t.suffix == ".md" and t.exists()]
    missing = [p.name for p in (REPO_ROOT / "docs").glob("*.md") if p.resolve() not in seen]
    assert not missing, f"docs pages no link from README.md reaches: {missing}"


def test_the_readme_is_a_front_page() -> None:
    text = (REPO_ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert "\n## Results\n" in text
