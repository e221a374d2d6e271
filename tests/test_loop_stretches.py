"""How the loop hands steps to a fast step's stretches (amronet.sim.loop.Loop.execute)."""

import numpy as np

from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.loop import Loop

CASE = ("agent-assisted-office", {"algorithm.params.explorer": "frontier", "sim.time_limit": 300, "radio.r_c": 4.0})


def test_recorded_steps_are_taken_in_stretches(monkeypatch):
    # a stretch may end on the step that is recorded: the loop then takes no step of its own to reach it (the
    # stretches give the step-by-step run bit for bit: tests/test_agent_stretch.py)
    sc = load_scenario(*CASE)
    every = sc.sim.record_every
    single: list[int] = []
    step = Loop.step

    def counted(self):
        single.append(self.steps + 1)  # the step it takes, counted from 1
        step(self)

    monkeypatch.setattr(Loop, "step", counted)
    sim = Simulation(sc, 2)
    sim.run()
    records = len(sim.rows) - 1  # (the first row is the initial state)
    assert records > 10
    recorded_alone = [k for k in single if k % every == 0]
    assert len(recorded_alone) < records // 4


def test_a_stretch_takes_the_relocators_look_after_a_router_is_put_down(monkeypatch):
    # the relocator must look at the links of a router put down (they change what it watches); the stretch that
    # follows takes that look itself where it can start no move (RepairStep._look), instead of a step of the loop's
    from amronet.engine.robots import Role, State
    from amronet.experiments.failures import _scenario

    sc = load_scenario(_scenario("agent-assisted-relocate", "office-32x32", 0.2, 600.0, 600.0, "frontier", "unit-disk"))
    quiet_single: list[int] = []
    step = Loop.step

    def counted(self):
        sw, faults = self.swarm, self.runs[0].faults
        if not (sw.state == State.RELOCATING).any() and not faults.pending(self.t):
            quiet_single.append(self.steps)
        step(self)

    monkeypatch.setattr(Loop, "step", counted)
    sim = Simulation(sc, 11)
    sim.run()
    routers = int(np.count_nonzero(sim.swarm.role == Role.ROUTER))
    assert routers > 20
    assert len(quiet_single) < routers // 3
