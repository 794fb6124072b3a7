"""HierarchicalIRL, observations and the problem helpers against independent truth: the
command line (the same C++ code must give the same bits), brute-force enumeration of
every trajectory of a tiny random MDP, and bad input refused naming the argument."""
import itertools
import json
import os
import subprocess
import numpy as np
import pytest

import hbirl
from conftest import assert_releases_the_gil

CLI = os.environ.get("HBIRL_CLI")


def cli(*args):
    if not CLI:
        pytest.skip("HBIRL_CLI (the hbirl command) not set: run through ctest")
    return subprocess.run([CLI, *args], check=True, capture_output=True, text=True).stdout


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    """A small confounded Gridworld (3 confounders, a labeller's contexts, a controlled
    run) as a problem file."""
    problem = hbirl.gridworld(size=4, trajectories=8, length=8, confounders=3, per_step=10, controlled=10, seed=5)
    path = str(tmp_path_factory.mktemp("grid") / "grid.json")
    problem.save(path)
    return problem, path


def test_gridworld_is_hbirl_generate_gridworld(tmp_path):
    problem = hbirl.gridworld(size=4, trajectories=8, length=8, confounders=3, per_step=10, controlled=10, seed=5)
    mine = tmp_path / "mine.json"
    problem.save(str(mine))
    theirs = json.loads(cli("generate", "gridworld", "--size", "4", "--trajectories", "8", "--length", "8", "--confounders", "3",
                            "--per-step", "10", "--controlled", "10", "--seed", "5"))
    theirs.pop("comment")
    assert json.loads(mine.read_text()) == theirs


@pytest.mark.parametrize("flags, params", [
    ([], {}),
    (["--eta", "stated"], {"eta": "stated"}),
    (["--alpha-update", "paper", "--restarts", "2"], {"alpha_update": "paper", "restarts": 2}),
    (["--engine", "mcmc", "--mcmc-samples", "40", "--mcmc-burn-in", "10", "--max-em-iterations", "4"],
     {"engine": "mcmc", "mcmc_samples": 40, "mcmc_burn_in": 10, "max_em_iterations": 4}),
    (["--em-theta-tolerance", "0.01", "--learn-observation-model", "false", "--c", "0.3", "--alpha-update", "paper"],
     {"em_theta_tolerance": 0.01, "learn_observation_model": False, "c": 0.3, "alpha_update": "paper"}),
])
def test_fit_gives_hbirl_learns_theta_bit_for_bit(grid, flags, params):
    problem, path = grid
    out = json.loads(cli("learn", "--problem", path, *flags))
    model = hbirl.HierarchicalIRL(**params).fit(problem.mdp, problem.observations(), problem.observation_prior)
    assert model.theta_.tolist() == out["weights"]  # the same doubles, not close ones
    assert model.log_likelihood_ == out["log_likelihood"]
    assert model.n_iter_ == out["em_iterations"]
    if "learned_eta" in out["observation_model"]:
        learned = np.array([c["learned"] for c in out["observation_model"]["learned_eta"]])
        assert np.array_equal(model.learned_eta_["learned"], learned)
    else:
        assert model.learned_eta_ is None
    subject = model.observation_model_["subject"]
    for s, a, row in out["observation_model"]["subject"]:
        assert subject[s, a].tolist() == row


@pytest.fixture(scope="module")
def with_catch_all(grid, tmp_path_factory):
    """The grid problem with a catch-all source for unlisted confounders."""
    doc = json.load(open(grid[1]))
    doc["observation_model"]["unlisted_source"] = {"eta": 0.1}
    path = str(tmp_path_factory.mktemp("unlisted") / "unlisted.json")
    with open(path, "w") as f:
        json.dump(doc, f)
    return hbirl.load_problem(path), path


@pytest.mark.parametrize("case, flags, params", [
    ("corridor", [], {}),  # terminal states: every trajectory ends in one
    ("unlisted", [], {}),
    # (200 samples: enough for a finite R-hat, which tells the stated eta's diagnostics from the learned eta's)
    ("unlisted", ["--engine", "mcmc", "--mcmc-samples", "200", "--mcmc-burn-in", "10", "--max-em-iterations", "3"],
     {"engine": "mcmc", "mcmc_samples": 200, "mcmc_burn_in": 10, "max_em_iterations": 3}),
])
def test_fit_gives_hbirl_learns_model_bit_for_bit(request, case, flags, params):
    if case == "corridor":
        path = os.path.join(os.environ.get("HBIRL_REPO", os.path.join(os.path.dirname(__file__), "..", "..")), "examples", "corridor.json")
        problem = hbirl.load_problem(path)
    else:
        problem, path = request.getfixturevalue("with_catch_all")
    out = json.loads(cli("learn", "--problem", path, *flags))
    model = hbirl.HierarchicalIRL(**params).fit(problem.mdp, problem.observations(), problem.observation_prior)
    assert model.theta_.tolist() == out["weights"]
    om = out["observation_model"]
    assert model.observation_model_["confounders"].tolist() == om["confounders"]
    for s, a, row in om["subject"]:
        assert model.observation_model_["subject"][s, a].tolist() == row
    if "mcmc_diagnostics" in out:  # JSON has no infinity: the CLI prints an infinite R-hat as null
        for key in ("worst_rhat", "worst_bulk_ess"):
            mine, theirs = model.mcmc_diagnostics_[key], out["mcmc_diagnostics"][key]
            assert mine == theirs or (theirs is None and not np.isfinite(mine)), (key, mine, theirs)
    if case == "corridor":  # the list form keeps the problem file's default: trajectories end in a terminal state
        again = hbirl.HierarchicalIRL(**params).fit(problem.mdp, problem.observations().to_list(), problem.observation_prior)
        assert again.theta_.tolist() == out["weights"]
    else:
        assert model.observation_model_["confounders"].shape[0] == 4  # 3 listed + the catch-all
        marginals, sources = model.posterior(problem.observations())
        assert sources.shape[1] == 5


def test_fitted_attributes_shapes_and_dtypes(grid):
    problem, _ = grid
    mdp, obs = problem.mdp, problem.observations()
    model = hbirl.HierarchicalIRL().fit(mdp, obs, problem.observation_prior)
    S, A, K = mdp.num_states, mdp.num_actions, mdp.num_features
    assert model.theta_.shape == (K,) and model.theta_.dtype == np.float64
    assert model.policy_.shape == (S, A)
    n = model.n_iter_
    assert n >= 2 and model.converged_
    assert model.history_["log_likelihood"].shape == (n,) and model.history_["theta"].shape == (n, K)
    np.testing.assert_array_equal(model.history_["theta"][-1], model.theta_)
    # EM's objective never decreases while the subject prior's strength stands.
    objective, strength = model.history_["objective"], model.history_["prior_strength"]
    same = strength[1:] == strength[:-1]
    assert same.any()
    assert np.all(np.diff(objective)[same] >= -1e-9 * np.abs(objective[1:][same]))
    assert model.observation_model_["subject"].shape == (S, A, 4)
    assert model.observation_model_["confounders"].shape == (3, 4)
    np.testing.assert_allclose(model.observation_model_["subject"].sum(axis=2), 1.0)
    eta = model.learned_eta_
    assert eta["stated"].shape == eta["learned"].shape == (4, 4)  # the labeller's four picks
    assert eta["observations"].sum() == obs.symbols.size
    assert model.score(obs) == pytest.approx(model.log_likelihood_, rel=1e-12)
    marginals, sources = model.posterior(obs)
    assert len(marginals) == len(obs) and all(m.shape == (8, S, A) for m in marginals)
    np.testing.assert_allclose([m.sum(axis=(1, 2)) for m in marginals], 1.0)
    assert sources.shape == (obs.symbols.size, 4)
    np.testing.assert_allclose(sources.sum(axis=1), 1.0)
    predicted = model.predict(obs)
    assert [p.shape for p in predicted] == [(8, 2)] * len(obs) and predicted[0].dtype == np.int64
    # The learned expert's states are the truth's more often than chance (1 in 16 cells).
    truth = problem.truth_trajectories()
    states_right = np.mean(np.concatenate([p[:, 0] == t[:, 0] for p, t in zip(predicted, truth)]))
    assert states_right > 0.5


def test_the_list_and_flat_forms_are_the_same_data(grid):
    problem, _ = grid
    flat = problem.observations()
    as_list = flat.to_list()
    again = hbirl.Observations.from_list(as_list)
    for name in ("symbols", "eta", "step_index", "lengths", "contexts"):
        np.testing.assert_array_equal(getattr(again, name), getattr(flat, name))
    prior = problem.observation_prior
    a = hbirl.HierarchicalIRL().fit(problem.mdp, as_list, prior).theta_
    b = hbirl.HierarchicalIRL().fit(problem.mdp, (flat.symbols, flat.eta, flat.step_index, flat.lengths, flat.contexts), prior).theta_
    assert a.tolist() == b.tolist()


def random_task(rng, S=3, A=2, W=3, E=1):
    T = rng.random((S, A, S)) + 0.05
    T /= T.sum(axis=2, keepdims=True)
    mdp = hbirl.Mdp(T, rng.normal(size=(S, A, 2)), discount=0.9)
    subject = rng.random((S, A, W)) + 0.1
    subject /= subject.sum(axis=2, keepdims=True)
    elements = rng.random((E, W)) + 0.1
    elements /= elements.sum(axis=1, keepdims=True)
    return T, mdp, subject, elements


def test_posterior_and_score_match_brute_force_enumeration():
    # A random 3-state MDP and sensor (not one of ours); the model is fixed to the prior's
    # mean (learn_observation_model=False, eta as stated), so for the fitted theta the
    # posterior is checked against summing over all 6^3 (s, a) paths by hand.
    rng = np.random.default_rng(11)
    S, A, W = 3, 2, 3
    T, mdp, subject, elements = random_task(rng, S, A, W)
    scale = 1e6  # alpha proportional to O with a huge total: the mean is O to 1e-6 relative
    prior = hbirl.ObservationPrior(mdp, W, 1, subject_alpha=subject * scale, confounder_alpha=elements * scale, learn=False,
                                   learn_eta=False)
    steps = []
    for t in range(3):
        n = int(rng.integers(0, 3))  # steps without observations (occlusion) too
        e = rng.random((n, 2))
        steps.append((rng.integers(0, W, n), e / e.sum(axis=1, keepdims=True)))
    obs = [steps]
    model = hbirl.HierarchicalIRL(max_em_iterations=3).fit(mdp, obs, prior)
    pi = mdp.soft_policy(model.theta_)
    O_s = model.observation_model_["subject"]
    O_e = model.observation_model_["confounders"]
    total = 0.0
    marg = np.zeros((3, S, A))
    src = [np.zeros((len(w), 2)) for w, _ in steps]
    for path in itertools.product(range(S * A), repeat=3):
        p = 1.0
        prev = None
        for t, r in enumerate(path):
            s, a = divmod(r, A)
            p *= (mdp.start[s] if prev is None else T[prev[0], prev[1], s]) * pi[s, a]
            w, e = steps[t]
            for k in range(len(w)):
                p *= e[k, 0] * O_s[s, a, w[k]] + e[k, 1] * O_e[0, w[k]]
            prev = (s, a)
        total += p
        for t, r in enumerate(path):
            s, a = divmod(r, A)
            marg[t, s, a] += p
            w, e = steps[t]
            for k in range(len(w)):
                mix = np.array([e[k, 0] * O_s[s, a, w[k]], e[k, 1] * O_e[0, w[k]]])
                src[t][k] += p * mix / mix.sum()
    marginals, sources = model.posterior(obs)
    np.testing.assert_allclose(marginals[0], marg / total, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sources, np.concatenate(src) / total, rtol=0, atol=1e-12)
    assert model.score(obs) == pytest.approx(np.log(total), rel=1e-12)


def test_mdp_from_rows_and_sparse_is_the_dense_mdp():
    rng = np.random.default_rng(2)
    T, mdp, _, _ = random_task(rng, S=5, A=3)
    rows = mdp.transition_rows()
    assert rows.shape == (5 * 3 * 5, 4)
    F = np.zeros((5, 3, 2))
    theta = np.array([0.3, -1.0])
    dense = hbirl.Mdp(T, rng.normal(size=(5, 3, 2)), discount=0.9)
    F = np.array([[s, a, k, dense.reward(np.eye(2)[k])[s, a]] for s in range(5) for a in range(3) for k in range(2)])
    from_rows = hbirl.Mdp(rows, F, discount=0.9)
    np.testing.assert_array_equal(from_rows.soft_policy(theta), dense.soft_policy(theta))
    scipy_sparse = pytest.importorskip("scipy.sparse")
    sparse = scipy_sparse.csr_matrix(T.reshape(15, 5))
    from_sparse = hbirl.Mdp(sparse, F, discount=0.9)
    np.testing.assert_array_equal(from_sparse.soft_policy(theta), dense.soft_policy(theta))


def test_optimal_policy_satisfies_the_bellman_optimality_equation():
    rng = np.random.default_rng(4)
    T, mdp, _, _ = random_task(rng, S=6, A=3)
    R = rng.normal(size=(6, 3))
    actions, V = mdp.optimal_policy(R)
    Q = R + 0.9 * T @ V
    np.testing.assert_allclose(V, Q.max(axis=1), atol=1e-8)
    assert all(Q[s, actions[s]] == pytest.approx(Q[s].max(), abs=1e-8) for s in range(6))


def test_controlled_run_prior_is_the_problems_subject_prior(tmp_path):
    problem = hbirl.gridworld(size=3, trajectories=2, length=5, confounders=1, per_step=5, controlled=4, seed=2)
    path = tmp_path / "g.json"
    problem.save(str(path))
    doc = json.loads(path.read_text())
    controlled = [d for d in doc["demonstration"] if d.get("controlled")]
    truth = [np.array(d["truth"]) for d in controlled]
    observations = [[(np.array([o[0] for o in step["observations"]], dtype=np.int64),
                      np.array([o[1][:1] for o in step["observations"]])) for step in d["steps"]] for d in controlled]
    alpha = hbirl.controlled_run_prior(problem.mdp, truth, observations, 4)
    np.testing.assert_array_equal(alpha, problem.observation_prior.subject_alpha(problem.mdp))


def test_save_and_load_round_trip(tmp_path):
    problem = hbirl.gridworld(size=3, trajectories=3, length=4, confounders=2, per_step=3, controlled=2, seed=9)
    path = str(tmp_path / "p.json")
    problem.save(path)
    again = hbirl.load_problem(path)
    for name in ("symbols", "eta", "step_index", "lengths", "contexts"):
        np.testing.assert_array_equal(getattr(again.observations(), name), getattr(problem.observations(), name))
    assert again.feature_names == problem.feature_names and again.true_weights.tolist() == problem.true_weights.tolist()


def test_onion():
    onion = hbirl.onion()
    assert (onion.mdp.num_states, onion.mdp.num_actions) == (len(onion.state_names), len(onion.action_names))
    assert onion.true_weights.shape == (onion.mdp.num_features,) == (len(onion.feature_names),)


def tiny(rng=None):
    rng = rng or np.random.default_rng(0)
    T, mdp, subject, elements = random_task(rng)
    prior = hbirl.ObservationPrior(mdp, 3, 1)
    e = np.array([[0.7, 0.3]] * 2)
    obs = [[(np.array([0, 2]), e), (np.array([1, 1]), e)]] * 3
    return mdp, prior, obs


@pytest.mark.parametrize("make, field", [
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([0]), np.array([[0.5, 0.6]]))]], p), "observations[0][0]: eta"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([0]), np.array([[np.nan, 1.0]]))]], p), "observations[0][0]: eta"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([7]), np.array([[0.5, 0.5]]))]], p), "observations[0][0]: symbol 7"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([0]), np.array([[1.0]]))]], p), "observations.eta"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([0, 1]), np.array([[1.0, 0.0]]))]], p), "observations[0][0]: eta"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[(np.array([0.5]), np.array([[1.0, 0.0]]))]], p), "observations[0][0]: symbols"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [[]], p), "observations[0]"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, [], p), "observations"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, (np.array([0, 1]), np.array([[1.0, 0], [1, 0]]), np.array([1, 0]), np.array([2])), p),
     "observations.step_index"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, (np.array([0]), np.array([[1.0, 0]]), np.array([5]), np.array([2])), p),
     "observations.step_index"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, (np.array([0]), np.array([[1.0, 0]]), np.array([0]), np.array([0])), p),
     "observations.lengths"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, (np.array([0]), np.array([[1.0, 0]]), np.array([0]), np.array([1 << 40])), p),
     "observations.lengths"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, o, "prior"), "prior"),
    (lambda m, p, o: hbirl.HierarchicalIRL(engine="gibbs").fit(m, o, p), "engine"),
    (lambda m, p, o: hbirl.HierarchicalIRL(eta="guessed").fit(m, o, p), "eta"),
    (lambda m, p, o: hbirl.HierarchicalIRL(mcmc_chains=0).fit(m, o, p), "mcmc_chains"),
    (lambda m, p, o: hbirl.HierarchicalIRL().score(o), "HierarchicalIRL: not fitted"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, subject_alpha=np.ones((2, 2, 3))), "subject_alpha"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, confounder_alpha=np.ones((2, 3))), "confounder_alpha"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, update="adam"), "update"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 0, 1), "num_symbols"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, unlisted_eta=1.0), "unlisted_eta"),
    (lambda m, p, o: hbirl.Mdp(np.array([[0, 0, 1e9, 1.0]]), np.zeros((1, 1, 1))), "transitions"),
    (lambda m, p, o: hbirl.Mdp(np.array([[0, 0, 0, 1.0], [5, 0, 0, 1.0]]), np.array([[0, 0, 0, 1.0]])), "num_states"),
    (lambda m, p, o: hbirl.Mdp(np.array([[0, 0.5, 0, 1.0]]), np.array([[0, 0, 0, 1.0]])), "transitions"),
    (lambda m, p, o: hbirl.gridworld(size=1), "size"),
    (lambda m, p, o: hbirl.gridworld(labeller_accuracy=2), "labeller_accuracy"),
    # fractions are refused, not truncated; sizes that would claim gigabytes are refused first
    (lambda m, p, o: hbirl.Observations([0.5], [[1.0, 0.0]], [0], [1]), "observations.symbols"),
    (lambda m, p, o: hbirl.Observations([0], [[1.0, 0.0]], [0.5], [1]), "observations.step_index"),
    (lambda m, p, o: hbirl.MaxCausalEntIRL().fit(m, [np.array([[0.5, 1.0]])]), "trajectories[0]"),
    (lambda m, p, o: hbirl.causal_log_likelihood(m, [np.array([[0, 1.5]])], [0.0, 0.0]), "trajectories[0]"),
    (lambda m, p, o: hbirl.HierarchicalIRL(restarts=2 ** 31 - 1).fit(m, o, p), "restarts"),
    (lambda m, p, o: hbirl.HierarchicalIRL(seed=-1).fit(m, o, p), "seed"),
    (lambda m, p, o: hbirl.HierarchicalIRL(max_iterations=2 ** 40).fit(m, o, p), "max_iterations"),
    (lambda m, p, o: hbirl.HierarchicalIRL(threads=10 ** 6).fit(m, o, p), "threads"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, o, hbirl.ObservationPrior(hbirl.Mdp(np.ones((1, 1, 1)), np.zeros((1, 1, 1))), 3, 1)),
     "prior"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, subject_alpha="x"), "subject_alpha"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1, prior_strength=None), "prior_strength"),
    (lambda m, p, o: hbirl.ObservationPrior(m, 3, 1 << 27), "num_confounders"),
    (lambda m, p, o: hbirl.Mdp(np.array([[0, 0, 0, 1.0]]), np.array([[0, 0, 0, 1.0]]), num_actions=2 ** 27), "num_actions"),
    (lambda m, p, o: hbirl.Mdp(np.array([[0, 0, 0, 1.0]]), np.array([[0, 0, 0, 1.0]]), num_features=2 ** 29), "num_features"),
    (lambda m, p, o: hbirl.controlled_run_prior(m, [np.array([[0, 0]])], [[(np.array([0]), np.array([[1.0]]))]], 1 << 30), "num_symbols"),
    (lambda m, p, o: hbirl.controlled_run_prior(m, [np.array([[0, 0], [1, 0]])], [[(np.array([0]), np.array([[1.0]]))]], 3), "truth"),
    (lambda m, p, o: hbirl.HierarchicalIRL(max_em_iterations=float("inf")).fit(m, o, p), "max_em_iterations"),
    (lambda m, p, o: hbirl.HierarchicalIRL(mcmc_samples=10 ** 8).fit(m, o, p), "mcmc_samples"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, hbirl.Observations([0], [[1.0, 0]], [0], [1], contexts=np.array([2 ** 64 - 1], dtype=np.uint64)), p),
     "observations.contexts"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, hbirl.Observations([True], [[1.0, 0]], [0], [1]), p), "observations.symbols"),
    (lambda m, p, o: hbirl.HierarchicalIRL().fit(m, hbirl.Observations([0], [[1.0, 0]], [0], [2 ** 26]), p), "observations.lengths"),
    (lambda m, p, o: hbirl.Mdp(np.ones((1, 1, 1)), np.zeros((1, 1, 1)), num_states=-1), "num_states"),
    (lambda m, p, o: hbirl.gridworld(trajectories=10 ** 7, length=10 ** 6), "trajectories"),
    (lambda m, p, o: hbirl.gridworld(size=4.5), "size"),
])
def test_bad_input_names_the_argument(make, field):
    mdp, prior, obs = tiny()
    with pytest.raises(ValueError) as e:
        make(mdp, prior, obs)
    assert str(e.value).startswith(field), str(e.value)
    assert "\n" not in str(e.value)


def test_a_huge_length_is_refused_before_anything_is_computed():
    mdp, prior, obs = tiny()
    model = hbirl.HierarchicalIRL(max_em_iterations=2).fit(mdp, obs, prior)
    huge = hbirl.Observations(np.zeros(0, int), np.zeros((0, 2)), np.zeros(0, int), [1, 2 ** 63 - 1])
    for call in (model.score, model.posterior, model.predict):
        with pytest.raises(ValueError, match="^observations.lengths"):
            call(huge)


def test_numbers_of_any_kind_and_the_subject_base():
    mdp, _, obs = tiny()
    fits = [hbirl.HierarchicalIRL(max_em_iterations=20).fit(mdp, obs, prior).theta_.tolist() for prior in (
        hbirl.ObservationPrior(mdp, 3, 1, subject_alpha=2.0),
        hbirl.ObservationPrior(mdp, 3, 1, subject_alpha=np.float32(2.0), confounder_alpha=np.int64(1)),
        hbirl.ObservationPrior(mdp, 3, 1, subject_alpha=np.full((3, 2, 3), 2.0), subject_alpha_default=2.0),
    )]
    assert fits[0] == fits[1] == fits[2]


def test_score_with_contexts_from_distinct_eta_and_unseen_contexts(grid):
    problem, _ = grid
    obs = problem.observations()
    auto = hbirl.Observations(obs.symbols, obs.eta, obs.step_index, obs.lengths)  # each distinct eta a context
    model = hbirl.HierarchicalIRL().fit(problem.mdp, auto, problem.observation_prior)
    assert model.learned_eta_ is not None
    assert model.score(auto) == pytest.approx(model.log_likelihood_, rel=1e-12)
    # Contexts fit never saw keep their stated eta: ids 9 and 10 (beyond the 4 learned) give
    # the same score as each other, and not the score with the learned rows.
    given = hbirl.HierarchicalIRL().fit(problem.mdp, obs, problem.observation_prior)
    one = [[(np.array([1]), np.array([[0.7, 0.1, 0.1, 0.1]]), np.array([c]))] for c in (9, 10, 0)]
    nine, ten, zero = (given.score([t]) for t in one)
    assert nine == ten != zero


def test_an_impossible_observation_is_named():
    rng = np.random.default_rng(0)
    _, mdp, _, _ = random_task(rng)
    subject = np.ones((3, 2, 3))
    subject[:, :, 2] = 0.0  # the subject never shows symbol 2, and eta says only it is seen
    prior = hbirl.ObservationPrior(mdp, 3, 1, subject_alpha=subject)
    with pytest.raises(ValueError, match=r"^observations\[0\]\.steps\[1\]\.observations\[0\]: impossible"):
        hbirl.HierarchicalIRL().fit(mdp, [[(np.array([0]), np.array([[1.0, 0.0]])), (np.array([2]), np.array([[1.0, 0.0]]))]], prior)


def test_fit_releases_the_gil(grid):
    problem, _ = grid
    mdp, obs, prior = problem.mdp, problem.observations(), problem.observation_prior
    assert_releases_the_gil(lambda: hbirl.HierarchicalIRL(threads=1, restarts=3).fit(mdp, obs, prior))


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_no_leak_over_a_thousand_fits():
    # Each fit allocates the E-step, the model and the results; a leak of a few hundred
    # bytes per fit would show as growth over 1,000 fits after a warm-up.
    mdp, prior, obs = tiny()
    trajectories = [np.array([[0, 1], [1, 0], [2, 1]])] * 4
    for _ in range(100):
        hbirl.MaxCausalEntIRL().fit(mdp, trajectories)
        hbirl.HierarchicalIRL(max_em_iterations=5).fit(mdp, obs, prior).posterior(obs)
    before = resident_bytes()
    for _ in range(1000):
        hbirl.MaxCausalEntIRL().fit(mdp, trajectories)
        hbirl.HierarchicalIRL(max_em_iterations=5).fit(mdp, obs, prior).posterior(obs)
    grown = resident_bytes() - before
    # 1 MiB over 1,000 iterations (two fits and a posterior each): under ~350 bytes a fit.
    assert grown < 1 << 20, f"resident memory grew by {grown} bytes over 1,000 iterations"


def test_a_fixed_observation_model_is_the_prior_learned_from(grid, tmp_path):
    # With O fixed (the file's "learn": false) and a controlled run, the model reported is
    # the controlled run's prior's mean -- what both the CLI and Python learned with.
    problem, path = grid
    doc = json.load(open(path))
    doc["observation_model"]["learn"] = False
    fixed = tmp_path / "fixed.json"
    fixed.write_text(json.dumps(doc))
    out = json.loads(cli("learn", "--problem", str(fixed)))
    model = hbirl.HierarchicalIRL(learn_observation_model=False).fit(problem.mdp, problem.observations(), problem.observation_prior)
    assert model.theta_.tolist() == out["weights"]
    alpha = problem.observation_prior.subject_alpha(problem.mdp)
    np.testing.assert_allclose(model.observation_model_["subject"], alpha / alpha.sum(axis=2, keepdims=True), rtol=1e-15)
    for s, a, row in out["observation_model"]["subject"]:
        assert model.observation_model_["subject"][s, a].tolist() == row


def test_load_domain_reads_a_service_set_domain_file(tmp_path):
    repo = os.environ.get("HBIRL_REPO", os.path.join(os.path.dirname(__file__), "..", ".."))
    path = os.path.join(repo, "examples", "warehouse.json")
    domain = hbirl.load_domain(path)
    doc = json.load(open(path))
    mdp = domain.mdp
    assert (mdp.num_states, mdp.num_actions, mdp.num_features) == (
        doc["mdp"]["num_states"], doc["mdp"]["num_actions"], doc["mdp"]["num_features"])
    prior = domain.observation_prior
    assert (prior.num_symbols, prior.num_confounders) == (
        doc["observation_model"]["num_symbols"], doc["observation_model"]["num_confounders"])
    assert domain.true_weights.shape == (mdp.num_features,)
    with pytest.raises(ValueError, match="^demonstration: has no trajectories"):
        domain.observations()
    doc["sensor"]["occlusion"] = 2.0
    bad = tmp_path / "bad_domain.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"bad_domain\.json: sensor\.occlusion"):
        hbirl.load_domain(str(bad))


def test_a_model_refuses_another_mdp_and_empty_steps_keep_their_width():
    mdp, prior, obs = tiny()
    model = hbirl.HierarchicalIRL(max_em_iterations=2).fit(mdp, obs, prior)
    other = hbirl.Mdp(np.full((4, 2, 4), 0.25), np.zeros((4, 2, 2)))
    model.mdp_ = other
    with pytest.raises(ValueError, match="^mdp: is not the MDP"):
        model.score(obs)
    model.mdp_ = mdp
    occluded = [[(np.zeros(0, int), np.zeros((0, 2)))] * 3]  # a trajectory seen at no step
    assert np.isfinite(model.score(occluded))
    marginals, sources = model.posterior(occluded)
    assert marginals[0].shape == (3, 3, 2) and sources.shape == (0, 2)


def test_a_pair_without_transitions_is_impossible_in_every_form():
    scipy_sparse = pytest.importorskip("scipy.sparse")
    T = np.zeros((2, 2, 2))
    T[0, 0, 1] = T[0, 1, 0] = T[1, 0, 0] = 1.0  # (1, 1) has none: impossible
    F = np.zeros((2, 2, 1))
    F[1, :, 0] = 1.0
    dense = hbirl.Mdp(T, F)
    for other in (hbirl.Mdp(scipy_sparse.csr_matrix(T.reshape(4, 2)), F), hbirl.Mdp(dense.transition_rows(), F)):
        np.testing.assert_array_equal(other.soft_policy([0.5]), dense.soft_policy([0.5]))
    assert dense.soft_policy([0.5])[1, 1] == 0.0


def test_the_estimators_parameters_are_hbirl_learns_settings():
    """One schema (app/learn_settings.hpp): HierarchicalIRL takes every setting of `hbirl
    learn`, with its default, MaxCausalEntIRL those that apply to true trajectories; each is
    documented in the class's docstring, and a value out of range is refused by name."""
    settings = hbirl._hbirl._learn_settings()
    names = [s["name"] for s in settings]
    assert list(hbirl.HierarchicalIRL().get_params()) == names
    truth_names = [s["name"] for s in settings if not s["observations_only"]]
    assert list(hbirl.MaxCausalEntIRL().get_params()) == truth_names
    assert "max_em_iterations" not in truth_names and "seed" in truth_names
    help_text = cli("learn", "--help")
    for s in settings:
        assert hbirl.HierarchicalIRL().get_params()[s["name"]] == s["default"]
        assert f"  {s['name']}: " in hbirl.HierarchicalIRL.__doc__
        assert f"--{s['name'].replace('_', '-')} " in help_text
    assert hbirl.HierarchicalIRL().get_params()["max_em_iterations"] == 300
    with pytest.raises(TypeError):
        hbirl.HierarchicalIRL(max_em_iteration=3)  # a misspelt setting


def test_the_posterior_is_hbirl_learns(grid):
    """posterior_ is `hbirl learn --posterior-samples`'s "posterior", from observations and
    from true trajectories (the same app function: app::posterior_summary)."""
    problem, path = grid
    out = json.loads(cli("learn", "--problem", path, "--posterior-samples", "30"))
    model = hbirl.HierarchicalIRL(posterior_samples=30).fit(problem.mdp, problem.observations(), problem.observation_prior)
    assert model.posterior_ == out["posterior"]
    assert 0.0 <= model.posterior_["confidence"] <= 1.0
    assert len(model.posterior_["interval_90"]) == problem.mdp.num_features
    truth = json.loads(cli("learn", "--problem", path, "--from", "truth", "--posterior-samples", "30", "--prior-scale", "2"))
    fitted = hbirl.MaxCausalEntIRL(posterior_samples=30, prior_scale=2).fit(problem.mdp, problem.truth_trajectories())
    assert fitted.posterior_ == truth["posterior"]
    assert hbirl.HierarchicalIRL().fit(problem.mdp, problem.observations(), problem.observation_prior).posterior_ is None


def end_task(rng, S=3, A=2, W=2, K=3):
    """A random MDP of S states and two terminal ones (a goal and a trap, say) that every
    action may enter, a subject sensor and an end sensor over the terminal states."""
    n = S + 2
    T = np.zeros((n, A, n))
    T[:S] = rng.random((S, A, n)) + 0.05
    T[:S] /= T[:S].sum(axis=2, keepdims=True)
    mdp = hbirl.Mdp(T, rng.normal(size=(n, A, 2)), start=np.r_[np.full(S, 1.0 / S), 0, 0], terminal=[S, S + 1],
                    discount=0.9)
    subject = rng.random((n, A, W)) + 0.1
    subject /= subject.sum(axis=2, keepdims=True)
    end = np.zeros((n, K))
    end[S:] = rng.random((2, K)) + 0.1
    end[S:] /= end[S:].sum(axis=1, keepdims=True)
    return T, mdp, subject, end


def test_end_reports_match_brute_force_enumeration():
    # An end sensor's reports (docs/MODEL.md "Sensors that see the end") through the Python
    # form: the posterior and score against summing over every (s, a) path and every
    # terminal state the last action may enter, by hand. O is fixed at the prior's mean.
    rng = np.random.default_rng(23)
    T, mdp, subject, end = end_task(rng)
    n, A, W = subject.shape
    S = n - 2
    scale = 1e6
    prior = hbirl.ObservationPrior(mdp, W, 0, subject_alpha=subject * scale, num_end_symbols=end.shape[1],
                                   end_alpha=end * scale, learn=False, learn_eta=False)
    steps = [[(rng.integers(0, W, 2), np.ones((2, 1))), (rng.integers(0, W, 1), np.ones((1, 1)))] for _ in range(2)]
    reports, known = [[0, 2], [1]], [-1, S + 1]
    obs = hbirl.Observations.from_list(steps, end_symbols=reports, end_state=known)
    model = hbirl.HierarchicalIRL(max_em_iterations=3).fit(mdp, obs, prior)
    np.testing.assert_allclose(model.observation_model_["end"][S:], end[S:], rtol=0, atol=1e-5)  # terminal rows
    pi = mdp.soft_policy(model.theta_)
    O_s = model.observation_model_["subject"]
    O_end = model.observation_model_["end"]
    marginals, _ = model.posterior(obs)
    score = 0.0
    for i, trajectory in enumerate(steps):
        total, marg = 0.0, np.zeros((2, n, A))
        for path in itertools.product(range(n * A), repeat=2):
            (s0, a0), (s1, a1) = divmod(path[0], A), divmod(path[1], A)
            p = mdp.start[s0] * pi[s0, a0] * T[s0, a0, s1] * pi[s1, a1]
            for t, (s, a) in enumerate([(s0, a0), (s1, a1)]):
                p *= np.prod(O_s[s, a, trajectory[t][0]])
            entered = [g for g in (S, S + 1) if known[i] in (-1, g)]
            p *= sum(T[s1, a1, g] * np.prod(O_end[g, reports[i]]) for g in entered)
            total += p
            marg[0, s0, a0] += p
            marg[1, s1, a1] += p
        np.testing.assert_allclose(marginals[i], marg / total, rtol=0, atol=1e-12)
        score += np.log(total)
    assert model.score(obs) == pytest.approx(score, rel=1e-12)
    # The reports matter: without them the posterior is another one.
    bare, _ = model.posterior(hbirl.Observations.from_list(steps))
    assert not np.allclose(bare[0], marginals[0], atol=1e-3)


def test_an_end_sensor_problem_fits_as_hbirl_learn_and_round_trips(tmp_path):
    path = str(tmp_path / "ended.json")
    cli("generate", "random-task", "--seed", "3", "--end-sensor", "--demonstrations", "12", "-o", path)
    out = json.loads(cli("learn", "--problem", path))
    problem = hbirl.load_problem(path)
    obs = problem.observations()
    assert obs.end_symbols is not None and sum(len(r) for r in obs.end_symbols) > 0
    prior = problem.observation_prior
    assert prior.num_end_symbols > 0 and prior.end_alpha.shape == (problem.mdp.num_states, prior.num_end_symbols)
    model = hbirl.HierarchicalIRL().fit(problem.mdp, obs, prior)
    assert model.theta_.tolist() == out["weights"]  # the same doubles, reports and all
    for s, row in out["observation_model"]["end_sensor"]:
        assert model.observation_model_["end"][s].tolist() == row
    # Through the list form, given back what it cannot carry: the same data.
    again = hbirl.Observations.from_list(obs.to_list(), end_symbols=obs.end_symbols, end_state=obs.end_state)
    assert hbirl.HierarchicalIRL().fit(problem.mdp, again, prior).theta_.tolist() == out["weights"]
    saved = str(tmp_path / "saved.json")
    problem.save(saved)
    reread = hbirl.load_problem(saved).observations()
    assert [r.tolist() for r in reread.end_symbols] == [r.tolist() for r in obs.end_symbols]
    # Without the reports the answer is another one (they are used, not just carried).
    bare = hbirl.Observations.from_list(obs.to_list())
    assert hbirl.HierarchicalIRL().fit(problem.mdp, bare, prior).theta_.tolist() != out["weights"]


@pytest.mark.parametrize("change, field", [
    (dict(end_state=[0, -1]), "observations.end_state"),  # not terminal
    (dict(end_state=[3]), "observations.end_state"),  # one per trajectory
    (dict(end_symbols=[[0], [5]]), "observations.end_symbols[1]"),  # not in [0, K)
    (dict(end_symbols=[[0]]), "observations.end_symbols"),  # one per trajectory
    (dict(end_symbols=[[[0]], []]), "observations.end_symbols[0]"),  # not 1-D
    (dict(end_symbols=[[0.5], []]), "observations.end_symbols[0]"),
    (dict(end_symbols=[list(range(3)) * 400, []]), "observations.end_symbols[0]"),  # more than an ending may have
    (dict(end_symbols=[[0], []], ends_in_terminal=[False, True]), "observations.end_symbols[0]"),
    (dict(end_state=[3, -1], ends_in_terminal=[False, True]), "observations.end_state"),
    (dict(end_symbols="01"), "observations.end_symbols"),
])
def test_bad_end_reports_are_refused_naming_the_field(change, field):
    _, mdp, subject, end = end_task(np.random.default_rng(1))
    prior = hbirl.ObservationPrior(mdp, 2, 0, num_end_symbols=3)
    steps = [[(np.array([0]), np.ones((1, 1)))]] * 2
    with pytest.raises(ValueError) as e:
        hbirl.HierarchicalIRL(max_em_iterations=2).fit(mdp, hbirl.Observations.from_list(steps, **change), prior)
    assert str(e.value).startswith(field), str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("make, field", [
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=-1), "num_end_symbols"),
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=1 << 20), "num_end_symbols"),
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3, end_alpha=np.ones((5, 2))), "end_alpha"),
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3, end_alpha=np.ones((5, 3))), "end_alpha"),  # non-terminal rows
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3, end_alpha=0.0), "end_alpha"),
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3, end_alpha=np.r_[np.zeros((4, 3)), np.ones((1, 3))]),
     "end_alpha"),  # terminal state 3's row sums to 0
    (lambda m: hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3, end_alpha_default=-1.0), "end_alpha_default"),
    (lambda m: hbirl.ObservationPrior(m, 2, 0, end_alpha=np.ones((5, 3))), "end_alpha"),  # no end sensor to give it to
    (lambda m: hbirl.ObservationPrior(m, 2, 0, end_alpha_default=2.0), "end_alpha_default"),
    (lambda m: hbirl.Observations.from_list(hbirl.Observations([0], [[1.0]], [0], [1]), end_state=[4]), "observations"),
    (lambda m: hbirl.ObservationPrior(hbirl.Mdp(np.ones((2, 1, 2)) / 2, np.zeros((2, 1, 1))), 2, 0, num_end_symbols=3),
     "num_end_symbols"),  # no terminal states to see
    (lambda m: hbirl.HierarchicalIRL().fit(hbirl.Mdp(np.ones((2, 1, 2)) / 2, np.zeros((2, 1, 1))),
                                           [[(np.array([0]), np.ones((1, 1)))]],
                                           hbirl.ObservationPrior(m, 2, 0, num_end_symbols=3)), "prior"),
])
def test_a_bad_end_sensor_prior_is_refused_naming_the_field(make, field):
    _, mdp, _, _ = end_task(np.random.default_rng(1))
    with pytest.raises(ValueError) as e:
        make(mdp)
    assert str(e.value).startswith(field), str(e.value)


def test_the_end_sensor_prior_reads_back():
    _, mdp, _, end = end_task(np.random.default_rng(2))
    assert hbirl.ObservationPrior(mdp, 2, 0).end_alpha is None
    prior = hbirl.ObservationPrior(mdp, 2, 0, num_end_symbols=3, end_alpha=2.5)
    expected = np.zeros((5, 3))
    expected[3:] = 2.5
    assert prior.num_end_symbols == 3 and prior.end_alpha.tolist() == expected.tolist()
    assert hbirl.ObservationPrior(mdp, 2, 0, num_end_symbols=3, end_alpha=end).end_alpha.tolist() == end.tolist()


def test_a_prior_tied_across_actions_fits_as_hbirl_learn(tmp_path):
    """observation_model.tie_actions: the file's setting reaches the Python prior, the fit is
    hbirl learn's bit for bit, and the tie changes the answer on a task whose controlled run
    shows a state's actions sharing their view."""
    path = str(tmp_path / "task.json")
    cli("generate", "random-task", "--seed", "1", "-o", path)
    doc = json.load(open(path))
    untied = json.loads(cli("learn", "--problem", path))
    doc["observation_model"]["tie_actions"] = True
    tied_path = str(tmp_path / "tied.json")
    with open(tied_path, "w") as f:
        json.dump(doc, f)
    out = json.loads(cli("learn", "--problem", tied_path))
    assert 0.0 < out["observation_model"]["tie_share"] < 1.0
    assert "tie_share" not in untied["observation_model"]
    assert out["weights"] != untied["weights"]
    problem = hbirl.load_problem(tied_path)
    assert problem.observation_prior.tie_actions
    model = hbirl.HierarchicalIRL().fit(problem.mdp, problem.observations(), problem.observation_prior)
    assert model.theta_.tolist() == out["weights"]
    assert hbirl.ObservationPrior(problem.mdp, 3, 0, tie_actions=True).tie_actions
    assert not hbirl.ObservationPrior(problem.mdp, 3, 0).tie_actions
