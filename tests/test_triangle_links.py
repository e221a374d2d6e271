"""Issue #44: a geometric triangle router settles only where its table row holds one of its references.

Under a radio whose links are not decided by distance alone (``multi-wall`` here), the paper's triangle rule drove a
router to a goal chosen by distance and settled it there, or where it gave up, behind walls from both references:
a deployed router cut off. The link test at settling (:meth:`GoalSteering.check_links`) sends it back to where it
last heard one.
"""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from amronet.algorithms.common.goto import GoalSteering
from amronet.engine.table import NeighbourTable

SOAK = Path(__file__).resolve().parents[1] / "tools" / "soak.py"


@pytest.fixture(scope="module")
def soak():
    spec = importlib.util.spec_from_file_location("amronet_soak_tool", SOAK)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def table_of(xy: np.ndarray, links: list[tuple[int, int]]) -> NeighbourTable:
    """A hand-built table holding only the given links (both ways), whatever the distances: walls cut the rest."""
    n = len(xy)
    linked = np.zeros((n, n), dtype=bool)
    for i, j in links:
        linked[i, j] = linked[j, i] = True
    rows, cols = np.nonzero(linked)
    indptr = np.concatenate([[0], np.cumsum(linked.sum(axis=1))]).astype(np.int64)
    dist = np.linalg.norm(xy[rows] - xy[cols], axis=1)
    return NeighbourTable(xy=xy, r=3.0, indptr=indptr, indices=cols.astype(np.int32), dist=dist,
                          threshold_dbm=-30.0, link_margin=np.full(len(rows), 2.0))


def test_check_links_settles_where_a_reference_is_heard_and_sends_the_others_back():
    # nodes 0 and 1: the references; 2 and 3: triangle routers bridging them; 4: a router that never heard one
    xy = np.array([[0.0, 0.0], [4.0, 0.0], [1.0, 0.0], [3.0, 0.0], [2.0, 2.0]])
    st = GoalSteering(5, n_anchors=2, give_up_steps=5)
    who = np.array([2, 3, 4])
    st.start(who, np.array([[2.0, 1.5]] * 3), np.array([[0, 1]] * 3))
    assert (st.refs[who] == [0, 1]).all() and np.isnan(st.heard_xy[who]).all()

    # on their way: 2 hears reference 0, 3 hears reference 1, 4 hears nothing; none is done
    settle, lost = st.check_links(who, np.zeros(3, dtype=bool), table_of(xy, [(0, 2), (1, 3)]), xy)
    assert not settle.any() and not lost.any()
    np.testing.assert_array_equal(st.heard_xy[2], [1.0, 0.0])
    np.testing.assert_array_equal(st.heard_xy[3], [3.0, 0.0])
    assert np.isnan(st.heard_xy[4]).all()

    # at their goals, behind walls from both references except 3 (it still hears 1): all three done
    at_goal = xy.copy()
    at_goal[[2, 3, 4]] = [[1.8, 1.5], [2.2, 1.5], [2.0, 2.0]]
    st.blocked_steps[2], st.last_to_goal[2] = 3, 0.5
    settle, lost = st.check_links(who, np.ones(3, dtype=bool), table_of(at_goal, [(1, 3)]), at_goal)
    assert settle.tolist() == [False, True, False]  # 3 hears a reference: it may settle
    assert lost.tolist() == [False, False, True]  # 4 never heard one: nowhere to go back to
    # 2 drives back to where it last heard 0, with no metre anchors on the way, its references kept
    assert st.retreating.tolist() == [False, False, True, False, False]
    np.testing.assert_array_equal(st.goal[2], [1.0, 0.0])
    assert (st.anchors[2] == -1).all() and (st.refs[2] == [0, 1]).all()
    assert st.last_to_goal[2] == np.inf and st.blocked_steps[2] == 0

    # back there but a reference is gone too: a second retreat is not tried, it is lost
    back = at_goal.copy()
    back[2] = [1.0, 0.0]
    settle, lost = st.check_links(np.array([2]), np.array([True]), table_of(back, []), back)
    assert settle.tolist() == [False] and lost.tolist() == [True]
    # or it hears its reference there again: it settles
    settle, lost = st.check_links(np.array([2]), np.array([True]), table_of(back, [(0, 2)]), back)
    assert settle.tolist() == [True] and lost.tolist() == [False]
    # a fresh start forgets the retreat
    st.start(np.array([2]), np.array([[2.0, 1.5]]), np.array([[0, 1]]))
    assert not st.retreating[2] and np.isnan(st.heard_xy[2]).all()


def test_grow_pads_the_link_state_too():
    st = GoalSteering(2, n_anchors=2, give_up_steps=5)
    st.grow(3)
    assert st.goal.shape == (5, 2) and st.refs.shape == (5, 2) and st.heard_xy.shape == (5, 2)
    assert st.retreating.shape == (5,) and (st.refs[2:] == -1).all() and np.isnan(st.heard_xy[2:]).all()
    st.start(np.array([4]), np.array([[1.0, 1.0]]), np.array([[0, 1]]))
    assert (st.refs[4] == [0, 1]).all()


@pytest.mark.parametrize(("seed", "index"), [(11, 1600), (11, 1752), (12, 839)],
                         ids=["autolab agent-assisted", "cave self-spreading", "cave self-spreading, global"])
def test_issue_44_soak_draws_keep_every_deployed_router_linked(soak, seed, index):
    """The three multi-wall draws (no shadowing, no packet loss) in which a triangle router settled cut off."""
    scenario, run_seed = soak.draw_scenario(seed, index)
    assert scenario["radio"]["model"] == "multi-wall" and not scenario["radio"].get("shadowing_db")
    checkers = []
    soak.run_checked(scenario, run_seed, checkers)
    findings = checkers[0].findings
    assert "router_cut_off" not in findings, findings["router_cut_off"].to_dict()
    assert all(f.known for f in findings.values()), {k: f.to_dict() for k, f in findings.items()}
