"""The Python package against independent truth: hand-solved MDPs, the command line (the
same C++ code must give the same bits), and bad input refused with a ValueError naming
the argument."""
import json
import os
import subprocess

import numpy as np
import pytest

import hbirl
from conftest import assert_releases_the_gil

REPO = os.environ.get("HBIRL_REPO", os.path.join(os.path.dirname(__file__), "..", ".."))
CORRIDOR = os.path.join(REPO, "examples", "corridor.json")


def chain(n=4, slip=0.1):
    """A chain of n states, actions left/right (each slips the other way with `slip`),
    the last state terminal; feature 0: being at the state before the end, 1: a step."""
    T = np.zeros((n, 2, n))
    for s in range(n - 1):
        left, right = max(s - 1, 0), s + 1
        T[s, 0, left] += 1 - slip
        T[s, 0, right] += slip
        T[s, 1, right] += 1 - slip
        T[s, 1, left] += slip
    F = np.zeros((n, 2, 2))
    F[n - 2, :, 0] = 1.0
    F[:, :, 1] = 1.0
    return hbirl.Mdp(T, F, terminal=[n - 1], discount=0.9)


def test_version_and_mdp_shapes():
    assert hbirl.__version__.count(".") == 2
    mdp = chain()
    assert (mdp.num_states, mdp.num_actions, mdp.num_features) == (4, 2, 2)
    assert mdp.discount == 0.9
    np.testing.assert_allclose(mdp.start, [1 / 3, 1 / 3, 1 / 3, 0])
    assert mdp.reward([1.0, -0.5]).shape == (4, 2)
    pi = mdp.soft_policy([1.0, -0.5])
    assert pi.shape == (4, 2)
    np.testing.assert_allclose(pi[:3].sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(pi[3], 0.0)  # terminal


def test_soft_values_solve_the_soft_bellman_equation():
    # Independent truth: V(s) = log sum_a exp(R(s, a) + gamma sum_s' P(s'|s,a) V(s')),
    # V = 0 at the terminal state, checked on the returned V.
    mdp = chain()
    theta = np.array([0.7, -0.2])
    V = mdp.soft_values(theta)
    R = mdp.reward(theta)
    n = 4
    T = np.zeros((n, 2, n))
    for s in range(n - 1):
        T[s, 0, max(s - 1, 0)] += 0.9
        T[s, 0, s + 1] += 0.1
        T[s, 1, s + 1] += 0.9
        T[s, 1, max(s - 1, 0)] += 0.1
    Q = R + 0.9 * T @ V
    assert V[3] == 0.0
    np.testing.assert_allclose(V[:3], np.log(np.exp(Q[:3]).sum(axis=1)), rtol=0, atol=1e-10)
    np.testing.assert_allclose(mdp.soft_policy(theta)[:3], np.exp(Q[:3] - V[:3, None]), atol=1e-10)


def test_fit_gives_the_command_lines_theta_bit_for_bit():
    problem = hbirl.load_problem(CORRIDOR)
    irl = hbirl.MaxCausalEntIRL().fit(problem.mdp, problem.truth_trajectories())
    cli = os.environ.get("HBIRL_CLI")
    if not cli:
        pytest.skip("HBIRL_CLI (the hbirl command) not set: run through ctest")
    out = subprocess.run([cli, "learn", "--from", "truth", "--problem", CORRIDOR], check=True, capture_output=True, text=True)
    weights = json.loads(out.stdout)["weights"]
    assert irl.theta_.tolist() == weights  # the same doubles, not close ones
    assert irl.policy_.shape == (problem.mdp.num_states, problem.mdp.num_actions)
    assert np.isfinite(irl.log_likelihood_)
    assert hbirl.ile(problem.mdp, problem.true_weights, irl.theta_) == pytest.approx(
        hbirl.ile(problem.mdp, problem.true_weights, np.array(weights)), abs=0)


def test_fit_recovers_the_goal_of_a_simulated_expert():
    # The expert prefers the state before the end; learned from its steps, the learned
    # reward's optimal behaviour is the expert's (ILE near 0).
    mdp = chain(6)
    truth = np.array([2.0, -0.1])
    pi = mdp.soft_policy(truth)
    rng = np.random.default_rng(3)
    P = np.zeros((6, 2, 6))
    for s in range(5):
        P[s, 0, max(s - 1, 0)] += 0.9
        P[s, 0, s + 1] += 0.1
        P[s, 1, s + 1] += 0.9
        P[s, 1, max(s - 1, 0)] += 0.1
    trajectories = []
    for _ in range(60):
        s, steps = int(rng.integers(0, 5)), []
        for _ in range(12):
            a = int(rng.choice(2, p=pi[s]))
            steps.append((s, a))
            s = int(rng.choice(6, p=P[s, a]))
            if s == 5:
                break
        trajectories.append(np.array(steps))
    irl = hbirl.MaxCausalEntIRL().fit(mdp, trajectories)
    assert hbirl.ile(mdp, truth, irl.theta_) < 0.05 * np.abs(mdp.soft_values(truth)).sum()
    assert irl.theta_[0] > 0


def test_estimator_parameters():
    irl = hbirl.MaxCausalEntIRL(l2=0.5)
    assert irl.get_params()["l2"] == 0.5
    assert irl.set_params(restarts=3) is irl and irl.restarts == 3
    with pytest.raises(ValueError, match="not a parameter"):
        irl.set_params(learning_rate=1)
    assert "l2=0.5" in repr(irl)


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: hbirl.Mdp(np.zeros((3, 2)), np.zeros((3, 2, 1))), "transitions"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), 0.5), np.zeros((3, 1, 1))), "features"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), 0.7), np.zeros((2, 1, 1))), "transitions"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), np.nan), np.zeros((2, 1, 1))), "transitions"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), 0.5), np.zeros((2, 1, 1)), terminal=[5]), "terminal"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), 0.5), np.zeros((2, 1, 1)), discount=1.0), "discount"),
        (lambda: hbirl.Mdp(np.full((2, 1, 2), 0.5), np.zeros((2, 1, 1)), start=[1.0]), "start"),
        (lambda: chain().soft_policy([1.0]), "theta"),
        (lambda: chain().soft_policy([np.inf, 0.0]), "theta"),
        (lambda: hbirl.MaxCausalEntIRL().fit(chain(), [np.array([[0, 5]])]), "trajectories[0]"),
        (lambda: hbirl.MaxCausalEntIRL().fit(chain(), [np.array([0, 1])]), "trajectories[0]"),
        (lambda: hbirl.MaxCausalEntIRL().fit(chain(), []), "trajectories"),
        (lambda: hbirl.MaxCausalEntIRL(optimizer="sgd").fit(chain(), [np.array([[0, 1]])]), "optimizer"),
        (lambda: hbirl.MaxCausalEntIRL(l2=-1).fit(chain(), [np.array([[0, 1]])]), "l2"),
        (lambda: hbirl.load_problem("/nonexistent/problem.json"), "/nonexistent/problem.json"),
    ],
)
def test_bad_input_is_a_value_error_naming_the_argument(make, field):
    with pytest.raises(ValueError) as e:
        make()
    assert str(e.value).startswith(field), str(e.value)
    assert "\n" not in str(e.value)


def test_a_bad_problem_file_names_the_file_and_the_field(tmp_path):
    doc = json.load(open(CORRIDOR))
    doc["mdp"]["discount"] = 1.5
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"bad\.json: mdp\.discount"):
        hbirl.load_problem(str(path))


def test_a_bad_recording_is_named_by_read_logs_arguments(tmp_path):
    # The readers are hbirl learn --log's: their errors name read_log's arguments, not its flags.
    damaged = tmp_path / "run.lcmlog"
    damaged.write_bytes(bytes(range(54)))  # 54 bytes of no recording
    with pytest.raises(ValueError) as e:
        hbirl.read_log(damaged)
    assert str(e.value).startswith(str(damaged) + ": "), str(e.value)
    assert "--" not in str(e.value) and "\n" not in str(e.value), str(e.value)
    with pytest.raises(ValueError) as e:
        hbirl.read_log(damaged, key=tmp_path / "absent.key")
    assert str(e.value).startswith(str(damaged) + ": key: "), str(e.value)
    assert "--" not in str(e.value), str(e.value)
    # A flag's letters inside a path are the path's.
    (tmp_path / "a--key").mkdir()
    in_odd_folder = tmp_path / "a--key" / "run.lcmlog"
    in_odd_folder.write_bytes(bytes(range(54)))
    with pytest.raises(ValueError) as e:
        hbirl.read_log(in_odd_folder)
    assert str(e.value).count(str(in_odd_folder)) == 2, str(e.value)  # the prefix, and in the message


def test_fit_releases_the_gil():
    # A thread that counts while a fit runs keeps counting: the GIL is free meanwhile.
    # (A dense random MDP of 300 states: a fit of a tenth of a second or more.)
    rng = np.random.default_rng(0)
    S, A, K = 300, 4, 8
    T = rng.random((S, A, S)) ** 8
    T /= T.sum(axis=2, keepdims=True)
    mdp = hbirl.Mdp(T, rng.random((S, A, K)), discount=0.95)
    trajectories = [np.column_stack([rng.integers(0, S, 40), rng.integers(0, A, 40)]) for _ in range(50)]
    assert_releases_the_gil(lambda: hbirl.MaxCausalEntIRL(threads=1).fit(mdp, trajectories))


def test_causal_log_likelihood_gradient_matches_finite_differences():
    # Independent truth: central differences of L itself; and L is the log-probability of
    # the demonstrated actions under the soft policy, summed (computed here in numpy).
    mdp = chain(6)
    rng = np.random.default_rng(5)
    trajectories = [np.column_stack([rng.integers(0, 5, 7), rng.integers(0, 2, 7)]) for _ in range(4)]
    theta = np.array([0.4, -0.3])
    value, gradient = hbirl.causal_log_likelihood(mdp, trajectories, theta)
    pi = mdp.soft_policy(theta)
    assert value == pytest.approx(sum(np.log(pi[t[:, 0], t[:, 1]]).sum() for t in trajectories), rel=1e-10)
    h = 1e-6
    for k in range(2):
        e = np.eye(2)[k] * h
        numeric = (hbirl.causal_log_likelihood(mdp, trajectories, theta + e)[0] -
                   hbirl.causal_log_likelihood(mdp, trajectories, theta - e)[0]) / (2 * h)
        assert gradient[k] == pytest.approx(numeric, rel=1e-5, abs=1e-7)
