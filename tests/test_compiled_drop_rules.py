"""Agent-assisted runs under every drop rule and realism switch: the compiled step against the phases, bit for bit."""

import numpy as np
import pytest

from amronet.algorithms.agent_assisted.controller import AgentAssisted
from amronet.algorithms.agent_assisted.drops.radius import Radius
from amronet.algorithms.agent_assisted.fast import CompiledAgents
from amronet.algorithms.agent_assisted.rule_check import RULE_CODES
from amronet.algorithms.agent_assisted.stretch import QuietStretch
from amronet.experiments.buildings import BUILDINGS, RADIOS
from amronet.experiments.common import agent_scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation

FRONTIER = {"algorithm.params.explorer": "frontier"}
WALLS = {"radio.model": "multi-wall", "radio.shadowing_db": 4.0}


def _hospital(rule, radio=None, agents=None):
    """The hospital floor plan as ``amronet reproduce buildings`` runs it (base at its west end, r_c 4 m)."""
    return agent_scenario("hospital_section", 4.0, ((3.0, 6.0),), 3, "frontier", 120.0, radio=radio, drop_rule=rule,
                          agents=agents)


CASES = {
    "radius": ("agent-assisted-office", 1, {**FRONTIER, "algorithm.params.drop_rule": "radius"}),
    "radius with its timer, random explorer": ("agent-assisted-office", 1, {
        "algorithm.params.drop_rule": "radius", "algorithm.params.drop": {"every_s": 20.0}}),
    "link-quality": ("agent-assisted-office", 2, {**FRONTIER, "algorithm.params.drop_rule": "link-quality"}),
    "link-quality under walls": ("agent-assisted-office", 2, {
        **FRONTIER, **WALLS, "algorithm.params.drop_rule": "link-quality"}),
    "distance-junction": ("agent-assisted-office", 3, {**FRONTIER, "algorithm.params.drop_rule": "distance-junction"}),
    "strip-goals": ("agent-assisted-office", 4, {**FRONTIER, "algorithm.params.drop_rule": "strip-goals"}),
    "when_empty continue": ("agent-assisted-office", 5, {
        **FRONTIER, "agents.when_empty": "continue", "agents.routers_carried": 3}),
    "drop_settle_s": ("agent-assisted-office", 6, {**FRONTIER, "agents.drop_settle_s": 2.0}),
    "drop_settle_s, strip-goals": ("agent-assisted-office", 6, {
        "agents.drop_settle_s": 2.0, "algorithm.params.drop_rule": "strip-goals"}),
    "reverse_drop under walls": ("agent-assisted-office", 7, {
        **FRONTIER, **WALLS, "agents.reverse_drop": 3.0, "algorithm.params.drop_rule": "distance-junction"}),
    "faults": ("agent-assisted-office", 8, {
        **FRONTIER, "faults": [{"at": 60.0, "routers": 0.5}], "sim.coverage_target": "off"}),
    "Poisson faults, radius": ("agent-assisted-office", 9, {
        "faults": [{"rate_per_hour": 60.0, "at": 30.0}], "algorithm.params.drop_rule": "radius"}),
    "four bases, triangles, link-quality": ("agent-assisted-office-4bs", 3, {
        **FRONTIER, "agents.per_base": 1, "algorithm.params.drop_rule": "link-quality"}),
    "four bases, triangles under walls (the link test at settling)": ("agent-assisted-office-4bs", 3, {
        **FRONTIER, "agents.per_base": 1, "radio.model": "multi-wall"}),
    **{f"hospital, {rule}, {radio}": (_hospital(rule, {"model": "multi-wall", "shadowing_db": 4.0} if radio == "walls"
                                                else None,
                                                {"routers_carried": 6, "when_empty": "continue"}), 70_001, {})
       for rule in ("last-reference", "link-quality", "radius", "distance-junction", "strip-goals")
       for radio in ("unit disk", "walls")},
}


def _counted(monkeypatch, calls):
    original = AgentAssisted.decide_tracked

    def counting(self, *args):
        calls.append(1)
        return original(self, *args)

    monkeypatch.setattr(AgentAssisted, "decide_tracked", counting)


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_step_gives_the_reference_run_bit_for_bit(name, monkeypatch):
    source, seed, overrides = CASES[name]
    sc = load_scenario(source, {"sim.time_limit": 150, **overrides} if isinstance(source, str) else overrides)
    compiled, reference = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    assert isinstance(compiled.compiled, CompiledAgents)
    calls: list[int] = []
    _counted(monkeypatch, calls)
    a = compiled.run()
    assert len(calls) < compiled.steps / 2  # most steps are quiet: the controller's Python is not asked
    b = reference.run()
    sw, ref = compiled.swarm, reference.swarm
    for x, y in ((sw.xy, ref.xy), (sw.heading, ref.heading), (sw.state, ref.state), (sw.status, ref.status),
                 (sw.distance, ref.distance)):
        np.testing.assert_array_equal(x, y)
    for attr in ("current", "left", "refused", "released_by", "pending_until", "reversing", "contact_since"):
        np.testing.assert_array_equal(getattr(compiled.controller, attr), getattr(reference.controller, attr))
    rule, other = compiled.controller.drop_rule, reference.controller.drop_rule
    for books in (("filter", "value"), ("turns", "samples"), ("last_drop",)):
        if hasattr(rule, books[0]):
            x, y = rule, other
            for part in books:
                x, y = getattr(x, part), getattr(y, part)
            np.testing.assert_array_equal(x, y)
    assert compiled.rows == reference.rows and a.network == b.network
    assert {k: v for k, v in a.summary.items() if k != "wall_time_s"} == \
        {k: v for k, v in b.summary.items() if k != "wall_time_s"}


@pytest.mark.parametrize(("rule", "stretches"), [("radius", True), ("distance-junction", True),
                                                ("strip-goals", True), ("link-quality", True)])
def test_rules_the_kernel_checks_take_quiet_stretches(rule, stretches):
    """Under the unit disk with the frontier explorer, a rule the stretch kernel checks runs many steps per call."""
    sc = load_scenario("agent-assisted-office", {**FRONTIER, "sim.time_limit": 60, "algorithm.params.drop_rule": rule})
    sim = Simulation(sc, 2)
    sim.run()
    quiet = sim.compiled.quiet
    assert (quiet is not None) is stretches
    if stretches:
        assert quiet.ends["quiet"] > 0


def test_reverse_drops_take_quiet_stretches_and_give_the_reference_run():
    """Agents out of contact for ``reverse_drop`` seconds back up, in stretches too; the stretch keeps their paths."""
    b = BUILDINGS["depot"]  # (multi-wall: agents lose contact, and back up)
    sc = load_scenario(agent_scenario(b.map, b.r_c, (b.base,), 3, "frontier", 100.0, radio=RADIOS["multi-wall"],
                                      drop_rule="distance-junction", agents={"reverse_drop": 5.0}))
    stretched, reference = Simulation(sc, 70_001), Simulation(sc, 70_001, step="reference")
    quiet = stretched.compiled.quiet
    assert isinstance(quiet, QuietStretch)
    a, b = stretched.run(), reference.run()
    assert quiet.ends["quiet"] > 0 and stretched.controller.reverse_drops > 0
    assert quiet.backing_steps > 0  # the agents that back up do so in stretches too
    mine, theirs = stretched.controller, reference.controller
    np.testing.assert_array_equal(stretched.swarm.xy, reference.swarm.xy)
    for attr in ("contact_since", "reversing", "left", "current"):
        np.testing.assert_array_equal(getattr(mine, attr), getattr(theirs, attr))
    np.testing.assert_array_equal(mine.trails.last, theirs.trails.last)
    for m in range(len(mine.agents)):
        np.testing.assert_array_equal(mine.trails.path(m), theirs.trails.path(m))
    assert stretched.rows == reference.rows and a.network == b.network
    assert {k: v for k, v in a.summary.items() if k != "wall_time_s"} == \
        {k: v for k, v in b.summary.items() if k != "wall_time_s"}


def test_a_rule_the_check_does_not_know_takes_the_reference_path():
    """A rule of another class (here a subclass of ``radius``) may decide otherwise: the controller's Python runs."""

    class Mine(Radius):
        pass

    sim = Simulation(load_scenario("agent-assisted-office", {"sim.time_limit": 5,
                                                             "algorithm.params.drop_rule": "radius"}), 1)
    assert isinstance(sim.compiled, CompiledAgents)
    controller = sim.controller
    controller.drop_rule = Mine(controller.drop_rule.params, controller.drop_rule.context)
    assert type(controller.drop_rule) not in RULE_CODES
    assert controller.fast_step(sim.step_context()) is None
