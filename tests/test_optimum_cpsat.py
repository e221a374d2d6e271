"""The optional CP-SAT solver of ``amronet optimum``: the same answers as HiGHS where both prove them, honest bounds.

The tests that solve need OR-Tools (the ``optimum`` extra, installed by ``make install``); they are skipped without
it. The refusals run either way.
"""

import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import amronet.optimum.cpsat as cpsat
from amronet.cli import main
from amronet.errors import AmronetError
from amronet.optimum import build_instance, find_optimum
from amronet.optimum.heuristic import greedy_connected_cover
from amronet.optimum.model import MipResult
from amronet.optimum.reduce import reduce_instance
from amronet.optimum.stored import optimum_key, optimum_problem
from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap
from test_optimum import amronet_checks, brute_force, corridor

needs_ortools = pytest.mark.skipif(not cpsat.available(), reason="OR-Tools (the optimum extra) is not installed")


def rooms() -> OccupancyMap:
    cells = np.full((42, 122), OCCUPIED, dtype=np.int8)  # three 2 m rooms in a row, doors 0.5 m wide
    cells[1:-1, 1:-1] = FREE
    for c in (41, 81):
        cells[1:-1, c] = OCCUPIED
        cells[15:25, c] = FREE
    return OccupancyMap("rooms", 0.05, (0.0, 0.0), cells)


CASES = [
    (corridor(75), (0.3, 0.3), 1.0, 0.25, None),      # coverage alone needs 2, connectivity 3
    (corridor(140), (0.3, 0.3), 1.0, 0.25, None),
    (rooms(), (0.5, 1.0), 3.0, 0.5, None),
    (rooms(), (0.5, 1.0), 3.0, 0.5, {"model": "multi-wall", "wall_db": 30.0}),
]


@needs_ortools
@pytest.mark.parametrize("case", range(len(CASES)))
def test_cp_sat_proves_the_same_optimum_as_highs(case):
    omap, base, r_c, spacing, radio = CASES[case]
    highs = find_optimum(omap, [base], r_c, spacing, radio=radio, time_limit=20)
    sat = find_optimum(omap, [base], r_c, spacing, radio=radio, time_limit=20, solver="cp-sat")
    assert highs.optimal and sat.optimal
    assert sat.count == sat.lower == highs.count
    assert sat.solver["name"].startswith("OR-Tools CP-SAT") and highs.solver["name"].startswith("HiGHS")
    assert amronet_checks(sat) == (1.0, True)


@needs_ortools
def test_cp_sat_finds_the_true_optimum_from_a_poor_start():
    """From every site chosen, CP-SAT itself must find the optimum (by enumeration) and prove it."""
    inst = build_instance(corridor(75), [(0.3, 0.3)], 1.0, 0.5)
    red = reduce_instance(inst)
    assert inst.n_sites <= 32
    every = np.ones(red.n, dtype=bool)
    res = cpsat.solve_cpsat(red.rows, red.links, red.base_linked, 20, start=every)
    assert res.status == "optimal" and res.value == res.bound == brute_force(inst) < red.n
    assert (red.rows @ res.chosen.astype(int) > 0).all()


@needs_ortools
def test_a_start_that_is_already_optimal_is_proven_and_reported_as_the_start():
    inst = build_instance(corridor(98), [(0.3, 0.3)], 1.0, 0.25)
    red = reduce_instance(inst)
    best = find_optimum(corridor(98), [(0.3, 0.3)], 1.0, 0.25, time_limit=20).count
    start = greedy_connected_cover(red.rows, red.links, red.base_linked)
    assert start.sum() == best  # the greedy chain is the optimum here
    res = cpsat.solve_cpsat(red.rows, red.links, red.base_linked, 20, start=start)
    assert (res.status, res.chosen, res.bound) == ("optimal", None, float(best))


def test_the_start_is_handed_in_with_a_flow_along_its_tree():
    links = sp.csr_matrix(np.array([[0, 1, 0, 0], [1, 0, 1, 1], [0, 1, 0, 0], [0, 1, 0, 0]]))
    base = np.array([True, False, False, False])
    chosen = np.array([True, True, True, False])
    flow = cpsat.tree_flow(links, base, chosen)
    assert flow == {(-1, 0): 3, (0, 1): 2, (1, 2): 1}  # each arc carries its subtree; each site consumes one


def test_an_unknown_solver_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["optimum", "--map", "obstacles-6x6", "--base=-2.5,-2.5", "--rc", "3", "--solver", "gurobi",
                 "--out", str(tmp_path / "never")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --solver: unknown solver 'gurobi'") and "\n" not in err
    assert not (tmp_path / "never").exists()


def test_cp_sat_without_or_tools_says_how_to_install_it(monkeypatch, capsys):
    monkeypatch.setattr(cpsat, "available", lambda: False)
    with pytest.raises(AmronetError, match=r"^--solver: cp-sat needs OR-Tools; install it with pip install"):
        find_optimum("obstacles-6x6", [(-2.5, -2.5)], 3.0, 1.5, time_limit=5, solver="cp-sat")
    assert main(["optimum", "--map", "obstacles-6x6", "--base=-2.5,-2.5", "--rc", "3", "--solver", "cp-sat"]) == 2
    assert capsys.readouterr().err.strip().startswith("amronet: error: --solver: cp-sat needs OR-Tools")


@needs_ortools
def test_the_solver_is_part_of_the_stored_key_and_highs_keeps_the_old_key():
    def problem(**kw):
        return optimum_problem("obstacles-6x6", [(-2.5, -2.5)], 3.0, 1.5, **kw)

    assert optimum_key(problem()) == optimum_key(problem(solver="highs"))
    assert "engine" not in problem()["solver"]  # answers kept before the choice existed are still found
    assert optimum_key(problem(solver="cp-sat")) != optimum_key(problem())


def test_highs_goes_on_from_cp_sats_best_and_the_larger_bound_counts(monkeypatch):
    """CP-SAT stops with a weak bound and a placement: HiGHS starts from that placement and proves the optimum."""
    import amronet.optimum.solve as solve_mod

    seen = {}

    def weak(rows, links, base, time_limit, *, start, chain=None):
        seen["start"] = int(start.sum())
        return MipResult(None, None, 1.0, "time-limit", 0.01, 7)

    monkeypatch.setattr(solve_mod, "require_cpsat", lambda: None)
    monkeypatch.setattr(solve_mod, "solve_cpsat", weak)
    opt = find_optimum(corridor(75), [(0.3, 0.3)], 1.0, 0.25, time_limit=20, solver="cp-sat")
    assert seen["start"] >= opt.count == 3 and opt.optimal
    assert opt.solver["cp_sat"] == {"status": "time-limit", "seconds": 0.01, "branches": 7, "bound": 1.0}
    assert opt.solver["nodes"] >= 0 and opt.bounds["solver"] == 3  # HiGHS's proof, not CP-SAT's 1


def test_a_best_cp_sat_proves_optimal_is_not_searched_again(monkeypatch):
    import amronet.optimum.solve as solve_mod

    def proves(rows, links, base, time_limit, *, start, chain=None):
        return MipResult(None, None, float(start.sum()), "optimal", 0.01, 3)

    real_solve = solve_mod.solve

    def highs(model, k, time_limit, **kw):
        assert "incumbent" not in kw, "HiGHS must not search the whole model after CP-SAT's proof"
        return real_solve(model, k, time_limit, **kw)  # the set cover's bound, local search

    monkeypatch.setattr(solve_mod, "require_cpsat", lambda: None)
    monkeypatch.setattr(solve_mod, "solve_cpsat", proves)
    monkeypatch.setattr(solve_mod, "solve", highs)
    opt = find_optimum(corridor(75), [(0.3, 0.3)], 1.0, 0.25, time_limit=20, solver="cp-sat")
    assert opt.optimal and opt.count == 3 and opt.solver["status"] == "optimal"


@needs_ortools
def test_ctrl_c_after_a_cp_sat_search_is_still_python_s_keyboard_interrupt():
    """OR-Tools' own SIGINT handler outlived its search: a later Ctrl-C killed the process without a word."""
    script = (
        "import signal\n"
        "import amronet.optimum.cpsat as cpsat\n"
        "from amronet.optimum.reduce import reduce_instance\n"
        "from amronet.optimum import build_instance\n"
        "from test_optimum import corridor\n"
        "red = reduce_instance(build_instance(corridor(75), [(0.3, 0.3)], 1.0, 0.25))\n"
        "import numpy as np\n"
        "cpsat.solve_cpsat(red.rows, red.links, red.base_linked, 5, start=np.ones(red.n, dtype=bool))\n"
        "try:\n"
        "    signal.raise_signal(signal.SIGINT)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted as Python')\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          cwd=Path(__file__).parent)
    assert (done.returncode, done.stdout) == (0, "interrupted as Python\n"), done.stderr[-500:]


@needs_ortools
def test_ctrl_c_during_a_cp_sat_search_stops_it_at_once():
    red = reduce_instance(build_instance("office-32x32", [(1.0, 1.0)], 4.0, 2.0))
    start = np.ones(red.n, dtype=bool)
    sent = []

    def ctrl_c():
        time.sleep(1.0)
        sent.append(time.monotonic())
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    threading.Thread(target=ctrl_c, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        cpsat.solve_cpsat(red.rows, red.links, red.base_linked, 60, start=start)
    assert time.monotonic() - sent[0] < 5.0
