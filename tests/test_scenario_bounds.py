"""Numbers a scenario cannot mean: radio fields outside their physical ranges, counts and ids beyond any run.

Each is refused in one line naming the field (exit 2, nothing written) instead of overflowing somewhere inside.
"""

import math

import pytest

from amronet.cli import main
from amronet.engine.propagation import RADIO_BOUNDS
from amronet.limits import MAX_COUNT

PRESET = "self-spreading-6x6"
HUGE = ["9223372036854775808", "1000000000000000000000000000000", "1" + "0" * 400]


def _refused(tmp_path, capsys, argv, out_name="out") -> str:
    out = tmp_path / out_name
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amronet: error: ") and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []
    return lines[0]


def _run(*sets: str) -> list[str]:
    argv = ["run", "--preset", PRESET, "-q", "--no-snapshot", "--set", "sim.time_limit=2"]
    for s in sets:
        argv += ["--set", s]
    return argv


@pytest.mark.parametrize("sets", [
    ["radio.model=log-distance", "radio.shadowing_db=1e6"],
    ["radio.model=log-distance", "radio.path_loss_exponent=1e-300"],
    ["radio.model=multi-wall", "radio.path_loss_exponent=1e-300"],
    ["radio.model=multi-wall", "radio.shadowing_db=9223372036854775808"],
])
def test_the_reported_overflows_are_one_line(tmp_path, capsys, sets):
    field = sets[-1].split("=")[0]
    line = _refused(tmp_path, capsys, _run(*sets))
    lo, hi = RADIO_BOUNDS[field.removeprefix("radio.")][:2]
    assert line.startswith(f"amronet: error: {field}: ") and f"is outside [{lo:g}, {hi:g}]" in line, line


def _values(name: str) -> list[str]:
    lo, hi = RADIO_BOUNDS[name][:2]
    below = [f"{lo - 1:g}"] + (["1e-300", "0"] if lo > 0 else [])
    return [*below, f"{hi + 1:g}", "1e300", "-1e300", ".inf", "-.inf", ".nan", *HUGE]


@pytest.mark.parametrize(("name", "value"), [(n, v) for n in RADIO_BOUNDS for v in _values(n)])
def test_every_radio_field_out_of_its_range_is_refused_with_the_range(tmp_path, capsys, name, value):
    model = "multi-wall" if name == "wall_db" else "log-distance"
    line = _refused(tmp_path, capsys, _run(f"radio.model={model}", f"radio.{name}={value}"))
    bound = RADIO_BOUNDS[name]
    assert line.startswith(f"amronet: error: radio.{name}: "), line
    assert f"is outside [{bound.lo:g}, {bound.hi:g}]" in line and f"give e.g. {bound.example:g}" in line, line


def test_the_radio_map_refuses_them_too(tmp_path, capsys):
    line = _refused(tmp_path, capsys, ["radio-map", "--map", "autolab", "--node", "2.5,10", "--radio", "log-distance",
                                       "--set", "radio.path_loss_exponent=1e-300"], "signal.png")
    assert "radio.path_loss_exponent: 1e-300 is outside [1, 8]" in line, line


@pytest.mark.parametrize("model", ["log-distance", "multi-wall"])
def test_the_extremes_of_every_range_run(tmp_path, capsys, model):
    """The widest reach the bounds allow (sigma 30 dB at n = 1: 10^9 r_c) and the strongest walls run cleanly."""
    sets = [f"radio.model={model}", "radio.shadowing_db=30", "radio.path_loss_exponent=1",
            "radio.shadowing_corr_m=0.1", "radio.tx_dbm=60", "radio.pl0_db=0"]
    if model == "multi-wall":
        sets.append("radio.wall_db=60")
    assert main([*_run(*sets), "--out", str(tmp_path / "a")]) == 0
    sets = [f"radio.model={model}", "radio.path_loss_exponent=8", "radio.shadowing_corr_m=1000",
            "radio.threshold_dbm=-174", "radio.tx_dbm=-60", "radio.pl0_db=100"]
    assert main([*_run(*sets), "--out", str(tmp_path / "b")]) == 0
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize(("preset", "override", "field"), [
    (PRESET, "routers.count={}", "routers.count"),
    (PRESET, "sim.record_every={}", "sim.record_every"),
    (PRESET, "faults=[{{at: 10, ids: [{}]}}]", "faults[0].ids[0]"),
    (PRESET, "faults=[{{at: 10, ids: [3, {}]}}]", "faults[0].ids[1]"),
    (PRESET, "faults=[{{at: 10, base_station: {}}}]", "faults[0].base_station"),
    (PRESET, "algorithm.params.give_up_steps={}", "algorithm.params.give_up_steps"),
    ("dssa-6x6", "algorithm.params.oscillation_limit={}", "algorithm.params.oscillation_limit"),
    ("dssa-6x6", "algorithm.params.stable_steps={}", "algorithm.params.stable_steps"),
    ("potential-field-6x6", "algorithm.params.connectivity_k={}", "algorithm.params.connectivity_k"),
    ("potential-field-6x6", "algorithm.params.rest_steps={}", "algorithm.params.rest_steps"),
    ("agent-assisted-office", "agents.per_base={}", "agents.per_base"),
    ("agent-assisted-office", "agents.routers_carried={}", "agents.routers_carried"),
    ("agent-assisted-office", "algorithm.params.give_up_steps={}", "algorithm.params.give_up_steps"),
])
@pytest.mark.parametrize("value", HUGE[:2])
def test_counts_and_ids_beyond_any_run_are_one_line(tmp_path, capsys, preset, override, field, value):
    argv = ["run", "--preset", preset, "-q", "--no-snapshot", "--set", "sim.time_limit=2",
            "--set", override.format(value)]
    line = _refused(tmp_path, capsys, argv)
    assert line.startswith(f"amronet: error: {field}: input should be less than"), line
    assert f"{MAX_COUNT}" in line, line


def test_a_count_at_the_limit_meets_the_memory_guard_not_an_overflow(tmp_path, capsys):
    line = _refused(tmp_path, capsys, _run(f"routers.count={MAX_COUNT}", "routers.start=uniform"))
    assert line.startswith("amronet: error: routers.count: "), line
    assert math.isfinite(MAX_COUNT) and MAX_COUNT < 2**62
