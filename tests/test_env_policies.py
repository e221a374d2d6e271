"""The paper's rules as policies of an observation deploy what the built-in controllers deploy (same seed, same
routers in the same places)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from amronet import Simulation, load_scenario
from amronet.engine.robots import Role
from amronet.env import deployment_env, policies, router_env


def _through_env(env, policy_cls, seed, **kwargs):
    policy = policy_cls(env, **kwargs)
    obs, _ = env.reset(seed=seed)
    policy.reset()
    while env.agents:
        obs, *_ = env.step(policy({a: obs[a] for a in env.agents}))
    return env.sim


def _builtin(preset, overrides, seed, steps):
    sim = Simulation(load_scenario(preset, overrides), seed)
    for _ in range(steps):
        sim.step()
    return sim


def _same_routers(a, b, at_least):
    routers = a.swarm.role == Role.ROUTER
    assert np.count_nonzero(a.swarm.deployed & routers) >= at_least
    assert len(a.swarm) == len(b.swarm)
    np.testing.assert_array_equal(a.swarm.xy, b.swarm.xy)
    np.testing.assert_array_equal(a.swarm.state, b.swarm.state)
    np.testing.assert_array_equal(a.swarm.status, b.swarm.status)


@pytest.mark.parametrize(("policy", "rule", "radio"), [
    (policies.LastReference, "last-reference", "unit-disk"),
    (policies.LinkQuality, "link-quality", "multi-wall"),
])
@pytest.mark.parametrize("actions", ["continuous", "discrete"])
def test_a_drop_rule_as_a_policy_deploys_what_the_controller_deploys(policy, rule, radio, actions):
    overrides = {"radio.model": radio, "agents.per_base": 2}
    env = deployment_env(overrides=overrides, max_steps=450, motion="builtin", actions=actions)
    through = _through_env(env, policy, seed=3)
    builtin = _builtin("agent-assisted-office", {**overrides, "algorithm.params.drop_rule": rule}, 3, 450)
    _same_routers(through, builtin, at_least=3)


def test_the_paper_rule_as_a_policy_settles_the_routers_the_controller_settles():
    env = router_env(max_steps=400, motion="builtin")
    through = _through_env(env, policies.LastReference, seed=2)
    builtin = _builtin("self-spreading-obstacles-6x6", {}, 2, through.steps)
    _same_routers(through, builtin, at_least=10)


def test_a_policy_with_another_threshold_deploys_differently():
    """The comparison above can fail: a rule that fires earlier drops other routers."""
    overrides = {"agents.per_base": 2}
    env = deployment_env(overrides=overrides, max_steps=450, motion="builtin")
    through = _through_env(env, policies.LinkQuality, seed=3, drop_margin_db=12.0)
    builtin = _builtin("agent-assisted-office", {**overrides, "algorithm.params.drop_rule": "link-quality"}, 3, 450)
    assert len(through.swarm) != len(builtin.swarm) or not np.array_equal(through.swarm.xy, builtin.swarm.xy)


def test_scripted_policies_steer_when_the_actions_move_the_agents():
    env = deployment_env(overrides={"agents.per_base": 2}, max_steps=200, actions="discrete")
    sim = _through_env(env, policies.LastReference, seed=1)
    assert sim.controller.released >= 1
    assert np.all(sim.swarm.distance[sim.controller.agents] > 1.0)


def test_the_link_quality_policy_follows_the_rule_sample_by_sample_restarts_included():
    from amronet.algorithms.agent_assisted.drops import DROP_RULES, AgentView, DropContext, validate_drop_params

    env = deployment_env(overrides={"agents.per_base": 1}, max_steps=5, motion="builtin")
    params = {"drop_margin_db": 6.0, "loss_margin_db": 1.0, "smoothing_s": 2.0}
    cls = DROP_RULES["link-quality"]
    rule = cls(validate_drop_params(cls, params, "drop"), DropContext(6.0, 5.7, env.sim.dt, 1, 2.0))
    policy = policies.LinkQuality(env, **params)
    rng = np.random.default_rng(7)
    dropped = False
    fired = 0
    for k in range(400):
        margin = float(rng.choice([-np.inf, rng.uniform(0, 12), rng.uniform(0, 40)], p=[0.05, 0.75, 0.2]))
        view = AgentView(t=k * 0.1, current=np.array([0 if np.isfinite(margin) else -1]), nearest_d=np.array([1.0]),
                         best_margin=np.array([margin]), xy=np.zeros((1, 2)), heading=np.zeros(1),
                         relay_xy=np.zeros((1, 2)), base_xy=np.zeros((1, 2)), in_contact=None, scans=None,
                         can_drop=np.array([True]))
        want = bool(rule.decide(view)[0])
        obs = {"relay": np.array([float(np.isfinite(margin)), 1.0, margin if np.isfinite(margin) else 0.0]),
               "flags": np.array([1, int(dropped), 1])}
        assert policy.wishes({"agent_0": obs})["agent_0"] == want, k
        dropped = want and rng.random() < 0.7  # (a drop may find no free spot)
        if dropped:
            rule.dropped(np.array([True]), view)
        fired += want
    assert 20 < fired < 380
