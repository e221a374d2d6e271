"""The warm-up (``amronet compile``): its cases reach every kernel that runs use, so a first run compiles nothing."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import amronet.sim.warmup as warmup
from amronet.algorithms.agent_assisted.drops.base import DROP_RULES
from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS
from amronet.algorithms.agent_assisted.warmups import driven_inside
from amronet.algorithms.base import ALGORITHMS, Controller
from amronet.algorithms.self_spreading.walks import WALKS
from amronet.cli.main import main
from amronet.engine.radio import MEDIA
from amronet.scenario import list_presets, load_scenario
from amronet.sim import Simulation
from amronet.sim.warmup import warmup_cases

ROOT = Path(__file__).resolve().parents[1]

# In a fresh process: warm up (loads the kernels from numba's cache, or compiles them if the cache is cold), then
# listen for numba compiling anything while runs that the warm-up did not list run: every built-in preset, and
# random scenarios of the soak (tools/soak.py: any map, algorithm and parameters, radio model, faults, robots), and
# the threaded kernels of large runs. Then list the kernels compiled for a literal argument.
_PROBE = """
import importlib.util, json, sys
from numba.core import event
from amronet.scenario import list_presets, load_scenario
from amronet.sim import Simulation
from amronet.sim.warmup import warm_up
from amronet.threads import threads_from

warm_up(jobs=1, large=True)  # with the threaded kernels of large runs (run below)
compiled = []

class Listener(event.Listener):
    def on_start(self, ev):
        d = ev.data["dispatcher"]
        compiled.append(d.py_func.__module__ + "." + d.py_func.__name__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Listener())
from amronet.patterns import place
for pattern in ("r-strip", "hexagonal"):  # Fig. 5's placed counts, amronet patterns
    place(pattern, (10.0, 6.0), 1.5)
for name in list_presets():
    Simulation(load_scenario(name, {"sim.time_limit": 3.0}), 1).run()
from amronet.experiments.common import CORNERS, agent_scenario
from amronet.sim.batch import run_seeds
for n in (1, 4):  # the figures' agents, long enough for their networks to meet (Fig. 7)
    Simulation(load_scenario(agent_scenario("office-32x32", 6.0, CORNERS[:n], 2, "frontier", 60.0)), 3).run()
run_seeds(load_scenario("self-spreading-obstacles-6x6", {"sim.time_limit": 3.0}), [1, 2, 3])  # Figs. 10/11
with threads_from(0):  # what a run of 30 000 robots or more runs
    Simulation(load_scenario("self-spreading-office", {"sim.time_limit": 3.0}), 1).run()
spec = importlib.util.spec_from_file_location("soak", sys.argv[1])
soak = importlib.util.module_from_spec(spec)
sys.modules["soak"] = soak
spec.loader.exec_module(soak)
for index in range(int(sys.argv[2])):
    scenario, seed = soak.draw_scenario(7, index, max_time=3.0)
    try:
        Simulation(load_scenario(scenario), seed).run()
    except Exception:
        pass  # a scenario the tool refuses (the soak counts those): what ran until then still counts
from numba.core.registry import CPUDispatcher
literal = sorted(f"{module}.{name}{sig}" for module, m in list(sys.modules.items()) if module.startswith("amronet")
                 for name, d in vars(m).items() if isinstance(d, CPUDispatcher) for sig in d.signatures
                 if "Literal" in str(sig))
print(json.dumps({"compiled": sorted(set(compiled)), "literal": literal}))
"""


def test_cases_cover_every_registered_name():
    cases = warmup_cases()
    assert {case.preset for case in cases} <= set(list_presets())
    for name, controller in ALGORITHMS.items():  # every algorithm's own runs, its defaults' run first
        assert controller.warm_ups()[0].label == f"algorithm {name}"
    labels = {case.label for case in cases}
    assert len(labels) == len(cases)
    for kind, names in (("explorer", driven_inside(EXPLORERS)), ("drop rule", driven_inside(DROP_RULES)),
                        ("walk", WALKS), ("radio", MEDIA), ("algorithm", ALGORITHMS)):
        assert {f"{kind} {name}" for name in names} <= labels
    # only what amronet.env drives is left out (it cannot run alone)
    assert set(EXPLORERS) - set(driven_inside(EXPLORERS)) == {"external"}
    assert set(DROP_RULES) - set(driven_inside(DROP_RULES)) == {"external"}


@pytest.mark.parametrize("name", sorted(ALGORITHMS))
def test_an_algorithm_with_a_fast_step_warms_it_up(name):
    """A registered algorithm that offers a fast step has a warm-up run that takes it (else its kernels compile in
    the user's first run)."""
    controller = ALGORITHMS[name]
    if controller.fast_step is Controller.fast_step:
        return
    fast = []
    for case in controller.warm_ups():
        sim = Simulation(load_scenario(case.preset, {"sim.time_limit": 1.0, **case.overrides}), case.seeds[0],
                         step=case.step)
        fast.append(sim.compiled is not None)
    assert any(fast), f"{name} offers a fast step but none of its warm-up runs takes it"


def test_self_spreadings_walk_and_link_quality_warm_ups_take_its_compiled_step():
    """Every walk rule and the link-quality rules step through the compiled kernels, so their warm-ups compile them."""
    cases = [case for case in ALGORITHMS["self-spreading"].warm_ups()
             if case.label.startswith("walk ") or "link-quality" in case.label]
    assert len(cases) == len(WALKS) + 1
    for case in cases:
        sim = Simulation(load_scenario(case.preset, {"sim.time_limit": 1.0, **case.overrides}), case.seeds[0],
                         step=case.step)
        assert sim.compiled is not None, case.label


def test_a_fast_step_missing_from_the_warm_up_is_found(monkeypatch):
    controller = ALGORITHMS["potential-field"]
    monkeypatch.setattr(controller, "warm_ups", classmethod(lambda cls: [
        warmup.WarmUp("algorithm potential-field", "potential-field-6x6", step="reference")]))
    with pytest.raises(AssertionError, match="offers a fast step"):
        test_an_algorithm_with_a_fast_step_warms_it_up("potential-field")


def test_after_the_warm_up_runs_compile_nothing():
    proc = subprocess.run([sys.executable, "-c", _PROBE, str(ROOT / "tools" / "soak.py"), "30"], cwd=ROOT,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    found = json.loads(proc.stdout.strip().splitlines()[-1])
    assert found["compiled"] == [], f"kernels the warm-up does not reach: {found['compiled']}"
    # a kernel calling another with a constant (True, 1) compiles it once more for that literal: pass np.bool_(True),
    # np.int64(1), which share the version the Python callers compile (each copy costs seconds of `amronet compile`)
    assert found["literal"] == [], f"kernels compiled for literal arguments: {found['literal']}"


def test_compile_command_refuses_bad_jobs(capsys):
    assert main(["compile", "--jobs", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "amronet: error: --jobs: must be >= 1, got 0"


def test_compile_interrupted_says_what_stays(monkeypatch, capsys):
    import amronet.sim.warmup as warmup

    def interrupted(**kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(warmup, "warm_up", interrupted)
    assert main(["compile", "--jobs", "1"]) == 130
    assert "the kernels compiled so far stay cached" in capsys.readouterr().err


def test_common_names_warm_up_cases():
    labels = {label for label, _ in warmup._tasks()}
    assert set(warmup.COMMON) <= labels
    frontier = next(c for c in warmup_cases() if c.label == "explorer frontier")
    assert frontier.first  # the longest chain of kernels starts first


def test_the_log_distance_hearing_kernels_start_beside_the_longest_chains():
    """Self-spreading's log-distance case starts with the first ones: agent-assisted's, which shares its hearing
    kernels, starts only once the frontier chain is done, and would otherwise wait for them in the other worker."""
    labels = warmup.task_labels()
    first = [case.label for case in warmup_cases() if case.first]
    assert "radio log-distance" in first
    ahead = labels.index("radio log-distance")
    assert ahead < labels.index("signal map") and ahead < labels.index("radio log-distance, agents")


def test_warm_up_runs_the_cases_named_and_notes_the_common_ones(monkeypatch):
    ran: list[int] = []
    noted: list[str] = []
    monkeypatch.setattr(warmup, "_run_case", lambda k: ran.append(k) or 0.0)
    monkeypatch.setattr(warmup, "mark_compiled", noted.append)
    keys = dict(warmup._tasks())
    warmup.warm_up(only=["walk growth"])
    assert ran == [keys["walk growth"]] and noted == []  # a few cases: nothing to note
    ran.clear()
    warmup.warm_up(only=warmup.COMMON)
    assert sorted(ran) == sorted(keys[label] for label in warmup.COMMON) and noted == ["common"]
    ran.clear()
    warmup.warm_up()
    assert sorted(ran) == sorted(keys.values()) and noted == ["common", "all"]
    with pytest.raises(ValueError, match="no warm-up case"):
        warmup.warm_up(only=["explorer nowhere"])


@pytest.mark.parametrize(("workers", "runs", "compiled", "expected"), [
    (2, 10, False, True),  # a cold cache, several workers: the warm-up
    (1, 10, False, False),  # one worker compiles each kernel once anyway
    (2, 1, False, False),  # one run compiles only what it uses
    (2, 10, True, False),  # compiled before (amronet compile, or an earlier sweep)
    (2, 10, None, False),  # not amronet's folder (NUMBA_CACHE_DIR): unknown, the runs compile
])
def test_warm_up_if_cold_only_when_the_kernels_were_never_compiled(monkeypatch, workers, runs, compiled, expected):
    calls = []
    monkeypatch.setattr(warmup, "compiled", lambda *names: compiled)
    monkeypatch.setattr(warmup, "warm_up", lambda **kw: calls.append(kw) or 12.5)
    said = []
    seconds = warmup.warm_up_if_cold(workers, runs, announce=lambda: said.append(1), initializer=print,
                                     initargs=("x",))
    assert (seconds == 12.5) is expected and (said == [1]) is expected
    if expected:
        assert calls == [{"jobs": workers, "only": warmup.COMMON, "initializer": print, "initargs": ("x",)}]


def test_a_failed_warm_up_leaves_the_runs_to_compile(monkeypatch):
    def broken(**kw):
        raise RuntimeError("a worker died")

    monkeypatch.setattr(warmup, "compiled", lambda *names: False)
    monkeypatch.setattr(warmup, "warm_up", broken)
    assert warmup.warm_up_if_cold(2, 10) is None


def test_sweeps_and_figures_warm_their_workers_first(monkeypatch, tmp_path):
    import amronet.sweeps.engine as engine
    from amronet.experiments.runner import run_jobs

    calls = []
    monkeypatch.setattr(engine, "warm_up_if_cold", lambda workers, runs, *a: calls.append((workers, runs)))
    sc = {"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"count": 5}, "sim": {"time_limit": 1.0}}
    jobs = [{"scenario": sc, "seed": s} for s in range(3)]
    run_jobs(jobs, workers=2, show_progress=False)
    run_jobs(jobs, workers=2, show_progress=False, store=tmp_path / "s.sqlite")
    assert calls == [(2, 3), (2, 3)]
