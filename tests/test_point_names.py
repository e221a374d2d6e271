"""Naming sweep points by their values (amronet.sweeps.point_names)."""

from __future__ import annotations

from amronet.sweeps.point_names import point_text, short_keys, value_text, varied_keys


def test_keys_are_shortened_to_their_last_component_when_unambiguous():
    assert short_keys(["radio.r_c", "algorithm.params.triangular"]) == {
        "radio.r_c": "r_c", "algorithm.params.triangular": "triangular"}
    assert short_keys(["agents.robot.max_speed", "routers.robot.max_speed", "radio.r_c"]) == {
        "agents.robot.max_speed": "agents.robot.max_speed", "routers.robot.max_speed": "routers.robot.max_speed",
        "radio.r_c": "r_c"}
    assert short_keys(["algorithm.params.loss_margin", "radio.loss_margin"]) == {
        "algorithm.params.loss_margin": "params.loss_margin", "radio.loss_margin": "radio.loss_margin"}
    assert short_keys(["r_c", "radio.r_c"]) == {"r_c": "r_c", "radio.r_c": "radio.r_c"}
    # a list index alone names nothing: it keeps the list's name
    assert short_keys(["base_stations.0.x", "base_stations.1.x"]) == {
        "base_stations.0.x": "base_stations.0.x", "base_stations.1.x": "base_stations.1.x"}


def test_only_the_keys_that_vary_are_shown_outer_grid_keys_first():
    labels = [{"figure": "fig10", "algorithm": a, "run": k} for a in ("dssa", "self-spreading") for k in range(3)]
    assert varied_keys(labels) == ["algorithm", "run"]
    sorted_grid = [{"a.triangular": t, "radio.r_c": r} for r in (0.8, 1.0) for t in ("local", "none")]
    assert varied_keys(sorted_grid) == ["radio.r_c", "a.triangular"]  # the store sorts keys; the points do not
    assert varied_keys([{"radio.r_c": 2.0}, {"radio.r_c": 2.0}]) == ["radio.r_c"]  # one point: all its keys
    assert varied_keys([{"radio.r_c": 1.0}, {"radio.r_c": 1.0, "map": "cave"}]) == ["map"]


def test_point_text_uses_the_short_names_and_plain_values():
    names = short_keys(["radio.r_c", "algorithm.params.triangular", "routers.count"])
    assert point_text({"radio.r_c": 2.5, "algorithm.params.triangular": "local"}, names) == (
        "r_c=2.5, triangular=local")
    assert value_text(1e-05) == "1e-05" and value_text([1, 2]) == "[1,2]" and value_text(None) == ""
