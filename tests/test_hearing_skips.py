"""A shortcut coverage under walls takes without changing a cell: a cell past the block's bound is skipped unasked.

:func:`~amronet.engine.hearing._heard_within2` lets the coverage kernel skip a cell by its squared distance alone:
no link that long is heard (whole-map equality is in ``test_coverage_reference.py``).
"""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.hearing import HearingInputs, _heard_within2, open_margin, path_loss_bound
from amronet.engine.propagation import LinkBudget


def _inputs(r_c: float, exponent: float, shadowing_db: float) -> HearingInputs:
    return HearingInputs.from_budget(LinkBudget(r_c=r_c, exponent=exponent, wall_db=6.9, shadowing_db=shadowing_db),
                                     None, None)._replace(clip=2.5 * shadowing_db)


@settings(max_examples=200, deadline=None)
@given(r_c=st.floats(1.0, 10.0), exponent=st.floats(1.5, 4.0), shadowing_db=st.sampled_from([0.0, 4.0, 8.0]),
       sa=st.floats(-3.0, 3.0), sb=st.floats(-3.0, 3.0), block=st.floats(0.0, 3.0), stretch=st.floats(1.0, 3.0))
def test_no_link_past_the_heard_distance_is_heard(r_c, exponent, shadowing_db, sa, sb, block, stretch):
    """Past the distance neither the bound nor the margin of a link whose ``sb`` is under the block's is >= 0."""
    h = _inputs(r_c, exponent, shadowing_db)
    s = sa + max(sb, sb + block) if h.clip > 0.0 else 0.0  # the block's largest value is at least this cell's
    far2 = _heard_within2(s, h)
    for d in (math.sqrt(far2) * (1.0 + 1e-12), math.sqrt(far2) * stretch + 1e-9):
        if d * d > far2:
            assert path_loss_bound(d, s, h) < 0.0
            assert open_margin(d, sa, sb, h.r_c, h.n10, h.corr, h.clip) < 0.0
    near = math.sqrt(far2) * (1.0 - 1e-6)  # just inside: the bound still allows it (so the skip is tight)
    assert path_loss_bound(near, s, h) >= 0.0
