"""Every example in README.md and docs/ runs: scenario YAML, sweep YAML, ``--set`` values, presets, Python snippets.

A documented value that the code refuses fails here. What is checked, per fenced block:

* a YAML block with ``map:`` and ``base_stations:`` is a scenario: it is loaded and validated, and its map is
  loaded and its robots placed (the run is set up, not run);
* a YAML block with ``scenario:`` and ``grid:`` (or ``seeds:``) is a sweep: it is loaded and validated;
* every ``amronet ...`` command line in any block: its ``--preset`` must exist, and every ``--set KEY=VALUE``
  must validate against the scenario the command names (the preset, or a scenario file written in the same page);
* a Python block runs, in a fresh temporary folder, unless the line before its fence is ``<!-- example: skip -->``
  (kept for snippets that need a cluster or minutes of runs);
* a tutorial (``docs/tutorials/*.md``, Jupytext Markdown notebooks) runs as a notebook would: its Python cells in
  order, in one namespace.
"""

from __future__ import annotations

import functools
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from amronet.scenario import load_scenario, parse_override
from amronet.scenario.loading import list_presets
from amronet.sim import Simulation

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
_FENCE = re.compile(r"^(?P<indent> *)```(?P<lang>[\w+-]*)[^\n]*\n(?P<body>.*?)^(?P=indent)```\s*$", re.M | re.S)
SKIP_MARK = "<!-- example: skip -->"


@dataclass(frozen=True)
class Block:
    """One fenced block of a page."""

    page: Path
    line: int
    lang: str
    body: str
    skip: bool

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks() -> list[Block]:
    """Every fenced block of every page, in order."""
    out = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for m in _FENCE.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            before = text[: m.start()].rstrip().rsplit("\n", 1)[-1].strip()
            body = "\n".join(row[len(m["indent"]):] for row in m["body"].splitlines())
            out.append(Block(page, line, m["lang"], body, before == SKIP_MARK))
    return out


BLOCKS = blocks()


def _is_scenario(doc: object) -> bool:
    return isinstance(doc, dict) and "map" in doc and "base_stations" in doc


@functools.cache
def _yaml_docs() -> list[tuple[Block, dict]]:
    from amronet.yaml_loading import load_yaml

    out = []
    for b in BLOCKS:
        if b.lang in ("yaml", "yml"):
            out.append((b, load_yaml(b.body, b.where)))
    return out


def _commands() -> list[tuple[Block, list[str]]]:
    """Every ``amronet`` command line of every block, split as a shell would (comments and continuations handled)."""
    out = []
    for b in BLOCKS:
        text = b.body.replace("\\\n", " ")
        for row in text.splitlines():
            row = row.strip().removeprefix("$ ")
            if not re.match(r"^(?:\.venv/bin/)?amronet\s", row):
                continue
            words = shlex.split(row, comments=True)
            out.append((b, words))
    return out


def test_the_pages_hold_examples():
    kinds = {b.lang for b in BLOCKS}
    assert "yaml" in kinds and "python" in kinds
    assert len(_commands()) >= 20


@pytest.mark.parametrize(("block", "doc"), [(b, d) for b, d in _yaml_docs() if _is_scenario(d)],
                         ids=lambda v: v.where if isinstance(v, Block) else "")
def test_scenario_examples_validate_and_set_up(block, doc, tmp_path):
    from amronet.sim.assemble import load_scenario_map

    scenario = load_scenario(doc)
    load_scenario_map(scenario)


@pytest.mark.parametrize(("block", "doc"), [(b, d) for b, d in _yaml_docs() if isinstance(d, dict) and
                                            "scenario" in d and ("grid" in d or "seeds" in d)],
                         ids=lambda v: v.where if isinstance(v, Block) else "")
def test_sweep_examples_validate(block, doc):
    from amronet.sweeps.spec import load_sweep

    load_sweep(doc)


def _scenario_of(words: list[str], page_scenarios: dict[str, dict]) -> object | None:
    """What the command's overrides apply to: its preset, a scenario written in the same pages, or None."""
    if "--preset" in words:
        return words[words.index("--preset") + 1]
    for w in words[2:]:
        if w.endswith((".yaml", ".yml")) and Path(w).name in page_scenarios:
            return page_scenarios[Path(w).name]
    return None


@functools.cache
def _named_scenarios(page: Path) -> dict[str, dict]:
    """Scenario examples written in the pages, by the file name their ``name`` gives them (``my-scenario.yaml``);
    those of ``page`` itself win over another page's of the same name, which its reader may never see."""
    named = {}
    for _block, doc in sorted(_yaml_docs(), key=lambda bd: bd[0].page == page):
        if _is_scenario(doc):
            named[f"{doc.get('name', 'scenario')}.yaml"] = doc
    return named


@pytest.mark.parametrize(("block", "words"), _commands(), ids=lambda v: v.where if isinstance(v, Block) else "")
def test_command_examples_name_real_presets_and_valid_overrides(block, words):
    presets = set(list_presets())
    if "--preset" in words:
        name = words[words.index("--preset") + 1]
        assert name in presets, f"{block.where}: unknown preset {name}"
    sets = [words[i + 1] for i, w in enumerate(words) if w == "--set"]
    if not sets:
        return
    target = _scenario_of(words, _named_scenarios(block.page))
    overrides = dict(parse_override(s) for s in sets)
    if target is None:  # a command that takes --set without a scenario (radio-map, plan): check the values parse
        return
    Simulation(load_scenario(target, overrides), seed=0)  # set up as the command would: its controller too


TUTORIALS = ROOT / "docs" / "tutorials"


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.lang == "python" and b.page.parent != TUTORIALS],
                         ids=lambda b: b.where)
def test_python_examples_run(block, tmp_path, monkeypatch):
    if block.skip:
        pytest.skip(f"{block.where} is marked {SKIP_MARK}")
    monkeypatch.chdir(tmp_path)
    code = compile(block.body, block.where, "exec")
    exec(code, {"__name__": "__doc_example__"})


@pytest.mark.parametrize("page", sorted(TUTORIALS.glob("*.md")), ids=lambda p: p.name)
def test_tutorials_execute_as_notebooks(page, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    cells = [b for b in BLOCKS if b.page == page and b.lang == "python"]
    assert cells, f"{page.name} has no Python cells"
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "__tutorial__"}
    try:
        for cell in cells:
            exec(compile(cell.body, cell.where, "exec"), namespace)
    finally:
        plt.close("all")
