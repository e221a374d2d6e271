"""The source tree's shape: no module over 400 lines (issue #35), so each file holds one responsibility."""

from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
MAX_LINES = 400


def _lines(path: Path) -> int:
    with path.open("rb") as fh:
        return sum(1 for _ in fh)


def test_no_source_file_is_over_400_lines():
    files = sorted(SRC.rglob("*.py"))
    assert files, f"no Python files under {SRC}"
    offenders = [(str(p.relative_to(SRC)), n) for p in files if (n := _lines(p)) > MAX_LINES]
    assert not offenders, (f"{len(offenders)} source file(s) over {MAX_LINES} lines; split them by responsibility: "
                           + ", ".join(f"{name} ({n})" for name, n in sorted(offenders, key=lambda o: -o[1])))


def test_every_algorithm_package_is_in_the_independence_contract():
    """An algorithm is one package under amronet/algorithms/; the contract that keeps them apart must name it."""
    import tomllib

    import amronet.algorithms as algorithms
    from amronet.algorithms.base import ALGORITHMS

    contracts = tomllib.loads((SRC.parent / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    independent = next(c for c in contracts if c["type"] == "independence")["modules"]
    packages = {f"amronet.algorithms.{p.name}" for p in Path(algorithms.__file__).parent.iterdir()
                if (p / "__init__.py").is_file() and p.name != "common"}
    assert packages == set(independent), f"list every algorithm package in the independence contract: {packages}"
    # every registered algorithm lives in one of them
    for cls in ALGORITHMS.values():
        assert any(cls.__module__.startswith(package + ".") for package in packages), cls.__module__
