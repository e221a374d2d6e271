"""The learning environments (amronet.env): the PettingZoo API, seeding, bounded observations, errors."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

pytest.importorskip("pettingzoo")
pytest.importorskip("gymnasium")

from pettingzoo.test import parallel_api_test

from amronet.env import EnvError, MissingExtraError, deployment_env, router_env
from amronet.env.vector import VecDeploymentEnv, VecRouterEnv
from amronet.errors import AmronetError, ScenarioError

OFFICE = {"agents.per_base": 2}


def _strict(env, cycles):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning of the API test is a failure here
        parallel_api_test(env, num_cycles=cycles)


@pytest.mark.parametrize("actions", ["continuous", "discrete"])
def test_the_agent_environment_passes_pettingzoos_parallel_api_test(actions):
    _strict(deployment_env(overrides=OFFICE, max_steps=60, actions=actions, seed=1, patch=9), 80)


@pytest.mark.parametrize("motion", ["policy", "builtin"])
def test_the_router_environment_passes_pettingzoos_parallel_api_test(motion):
    _strict(router_env(max_steps=60, motion=motion, actions="discrete", seed=1), 80)


def _rollout(env, seed, steps, action_seed):
    rng = np.random.default_rng(action_seed)
    obs, _ = env.reset(seed=seed)
    for space_name in env.possible_agents[:1]:
        env.action_space(space_name).seed(int(rng.integers(2**31)))
    trace = []
    for _ in range(steps):
        if not env.agents:
            break
        actions = {a: env.action_space(a).sample() for a in env.agents}
        obs, rewards, *_ = env.step(actions)
        trace.append(({a: {k: v.copy() for k, v in o.items()} for a, o in obs.items()}, dict(rewards)))
    return trace


def _same(t1, t2):
    assert len(t1) == len(t2)
    for (o1, r1), (o2, r2) in zip(t1, t2, strict=True):
        assert r1 == r2
        assert o1.keys() == o2.keys()
        for a in o1:
            for k in o1[a]:
                np.testing.assert_array_equal(o1[a][k], o2[a][k])


@pytest.mark.parametrize("make", [lambda: deployment_env(overrides=OFFICE, max_steps=40),
                                  lambda: router_env(max_steps=40)], ids=["agents", "routers"])
def test_the_same_seed_and_actions_give_the_same_observations_and_rewards(make):
    first = _rollout(make(), seed=5, steps=40, action_seed=2)
    again = _rollout(make(), seed=5, steps=40, action_seed=2)
    _same(first, again)
    other = _rollout(make(), seed=6, steps=40, action_seed=2)
    assert any(not np.array_equal(a[0][k1]["odometry"], b[0][k1]["odometry"])
               for a, b in zip(first, other, strict=False) for k1 in a[0] if k1 in b[0])


@pytest.mark.parametrize(("make", "wish_rate"), [
    (lambda: deployment_env(overrides={"radio.model": "multi-wall", **OFFICE}, max_steps=150, patch=7, seed=3), 0.5),
    (lambda: router_env(max_steps=150, seed=3, patch=5), 0.01)], ids=["agents", "routers"])
def test_observations_stay_in_their_space_over_a_random_policy_soak(make, wish_rate):
    env = make()
    rng = np.random.default_rng(4)
    seen = 0
    for seed in (11, 12):
        obs, _ = env.reset(seed=seed)
        while True:
            for a, o in obs.items():
                space = env.observation_space(a)
                assert space.contains(o), {k: (v.min(), v.max()) for k, v in o.items()}
                seen += 1
            if not env.agents:
                break
            actions = {}
            for a in env.agents:  # random motion; the wish (drop, settle) at the given rate
                act = env.action_space(a).sample()
                act[-1] = rng.random() < wish_rate
                actions[a] = act
            obs, *_ = env.step(actions)
    assert seen > 500


def test_the_agents_drop_routers_and_the_reward_counts_them():
    env = deployment_env(overrides=OFFICE, max_steps=30, motion="builtin", actions="discrete")
    env.reset(seed=2)
    before = env.sim.metrics().connected_coverage
    obs, rewards, _, _, infos = env.step(dict.fromkeys(env.agents, 1))  # both wish: each puts one router down
    assert env.sim.controller.released == 2
    assert all(obs[a]["flags"][1] == 1 for a in obs)  # "dropped"
    w, dt = env.config.reward, env.sim.dt
    gained = infos["agent_0"]["connected_coverage"] - before
    assert gained > 0
    for a, r in rewards.items():
        cut = 0.0 if infos[a]["connected"] else w.cut_off * dt
        assert r == pytest.approx(w.coverage * gained - w.router - cut)
    obs, rewards, *_ = env.step(dict.fromkeys(env.agents, 0))
    assert all(obs[a]["flags"][1] == 0 for a in obs)
    assert env.sim.controller.released == 2


@pytest.mark.parametrize(("call", "field"), [
    (lambda: deployment_env("no-such-preset"), "scenario"),
    (lambda: deployment_env(max_steps=-5), "max_steps"),
    (lambda: deployment_env(max_steps=2.5), "max_steps"),
    (lambda: deployment_env(motion="teleport"), "motion"),
    (lambda: deployment_env(actions="analog"), "actions"),
    (lambda: deployment_env(links=0), "links"),
    (lambda: deployment_env("self-spreading-6x6"), "scenario"),
    (lambda: router_env("agent-assisted-office"), "scenario"),
    (lambda: deployment_env(overrides={"radio.r_c": -1}), "radio.r_c"),
    (lambda: VecRouterEnv(seeds=[]), "seeds"),
])
def test_bad_arguments_are_one_line_errors_naming_the_field(call, field):
    with pytest.raises(AmronetError) as err:
        call()
    assert isinstance(err.value, EnvError | ScenarioError)
    assert err.value.field.startswith(field)
    assert "\n" not in str(err.value)


def test_an_action_outside_the_space_is_a_clear_error_and_changes_nothing():
    env = deployment_env(overrides=OFFICE, max_steps=10, seed=1)
    env.reset(seed=1)
    good = {a: np.array([0.0, 1.0, 0.0]) for a in env.agents}
    for bad, where in ((np.array([2.0, 1.0, 0.0]), "actions[agent_0]"), (np.array([np.nan, 1, 0]), "actions[agent_0]"),
                       (np.array([0.0, 1.0]), "actions[agent_0]"), ("left", "actions[agent_0]")):
        with pytest.raises(EnvError, match=r"outside the action space") as err:
            env.step({**good, "agent_0": bad})
        assert err.value.field == where
    with pytest.raises(EnvError, match="no action for 'agent_1'"):
        env.step({"agent_0": good["agent_0"]})
    with pytest.raises(EnvError, match="not an acting agent"):
        env.step({**good, "agent_9": good["agent_0"]})
    assert env.steps == 0 and env.sim.steps == 0
    env.step(good)  # float64 arrays from a NumPy policy are in the float32 space
    assert env.steps == 1


def test_the_external_rules_refuse_to_run_without_an_environment():
    from amronet import Simulation, load_scenario

    for overrides, field in (({"algorithm.params.explorer": "external"}, "algorithm.params.explorer"),
                             ({"algorithm.params.drop_rule": "external"}, "algorithm.params.drop_rule")):
        sim = Simulation(load_scenario("agent-assisted-office", overrides), 1)
        with pytest.raises(ScenarioError) as err:
            sim.step()
        assert err.value.field == field
    for overrides, field in (({"algorithm.params.walk": "external"}, "algorithm.params.walk"),
                             ({"algorithm.params.stop_rule": "external"}, "algorithm.params.stop_rule")):
        sim = Simulation(load_scenario("self-spreading-6x6", overrides), 1)
        with pytest.raises(ScenarioError) as err:
            sim.step()
        assert err.value.field == field


def test_the_vectorised_router_environment_steps_each_seed_as_the_single_one():
    vec = VecRouterEnv(seeds=[3, 4], max_steps=30, motion="builtin", actions="discrete")
    singles = [router_env(max_steps=30, motion="builtin", actions="discrete") for _ in range(2)]
    obs1 = [env.reset(seed=s)[0] for env, s in zip(singles, (3, 4), strict=True)]
    obs = vec.reset()
    rng = np.random.default_rng(0)
    for _ in range(30):
        if not vec.live.any():
            break
        wish = (rng.random(vec.live.shape) < 0.02).astype(np.int64)
        for g, env in enumerate(singles):
            names = env.possible_agents
            for r, a in enumerate(names):
                if a in obs1[g]:
                    np.testing.assert_array_equal(obs1[g][a]["relay"], obs["relay"][g, r])
                    np.testing.assert_array_equal(obs1[g][a]["scan"], obs["scan"][g, r])
            if env.agents:
                obs1[g], *_ = env.step({a: int(wish[g, names.index(a)]) for a in env.agents})
        obs, *_ = vec.step(wish)
    with pytest.raises(EnvError, match="outside the action space"):
        VecRouterEnv(seeds=[1], max_steps=5, motion="builtin", actions="discrete").step(np.full((1, 30), 7))


def test_the_vectorised_agent_environment_stacks_its_runs():
    vec = VecDeploymentEnv(seeds=[1, 2], overrides=OFFICE, max_steps=5)
    obs = vec.reset()
    assert obs["scan"].shape[:2] == (2, 2)
    for _ in range(5):
        obs, rewards, term, trunc, _ = vec.step(np.tile([0.0, 1.0, 0.0], (2, 2, 1)))
        assert rewards.shape == term.shape == (2, 2) and obs["relay"].shape == (2, 2, 3)
    assert trunc.all() and not vec.live.any()
    with pytest.raises(EnvError, match="every run has finished"):
        vec.step(np.zeros((2, 2, 3)))


def test_without_the_extra_amronet_works_and_amronet_env_says_what_to_install():
    code = ("import sys; sys.modules['pettingzoo'] = None; sys.modules['gymnasium'] = None\n"
            "import amronet, amronet.cli.main\n"
            "amronet.load_scenario('agent-assisted-office')\n"
            "try:\n    import amronet.env\nexcept ImportError as exc:\n    print(type(exc).__name__, '|', exc)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ("MissingExtraError | amronet.env needs pettingzoo and gymnasium (the optional extra 'rl'): "
                   "pip install 'amronet[rl]'")
    assert issubclass(MissingExtraError, AmronetError)
