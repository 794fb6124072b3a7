# %% [markdown]
# # hbirl in Python: learning what an expert wants from confounded observations
#
# A robot watches an expert walk a 5×5 grid towards a goal corner. Its camera reports
# positions, but two other people walk the same grid, and a labeller can only guess who
# each detection belongs to: every observation comes with a source distribution η
# (expert, person 1, person 2). We will
#
# 1. build the Gridworld MDP from numpy arrays (any MDP of yours is built the same way),
# 2. simulate the expert, the two people, the camera and the labeller,
# 3. learn the expert's reward with `hbirl.HierarchicalIRL` (Bogert & Doshi, IROS 2021:
#    the expert's path and each observation's source are hidden, the observation model and
#    η are learned),
# 4. look at the EM iterations, the posterior over the expert's path and the learned η,
# 5. compare with MaxCausalEnt IRL on the true paths (what a perfect tracker would give)
#    and with a learner that believes every observation is the expert's.
#
# Run it as `python3 examples/python/tutorial.py` (docs/python.md "Python" says how to make
# `import hbirl` work); it writes the figure to `tutorial.png` (or `--out PATH`).

# %%
import argparse
import sys

import matplotlib

in_notebook = "ipykernel" in sys.modules
if not in_notebook:
    matplotlib.use("Agg")  # as a script: a file, no window (this also runs on a server)
import matplotlib.pyplot as plt
import numpy as np

import hbirl

out = "tutorial.png"
if not in_notebook:
    parser = argparse.ArgumentParser(description="hbirl's Python tutorial")
    parser.add_argument("--out", default=out, help="where to write the figure (PNG)")
    out = parser.parse_args().out
rng = np.random.default_rng(7)

# %% [markdown]
# ## 1. The Gridworld as numpy arrays
#
# States are cells `s = row * 5 + column`; actions are up, right, down, left. A move goes
# where intended with probability 0.9 and otherwise to one of the other three moves'
# cells (walls keep you in place). Features: being in each corner. Transitions are an
# `(S, A, S)` array, features an `(S, A, K)` array.

# %%
n = 5
S, A, K = n * n, 4, 4
moves = [(-1, 0), (0, 1), (1, 0), (0, -1)]


def target(s, a):
    r, c = divmod(s, n)
    dr, dc = moves[a]
    r2, c2 = min(max(r + dr, 0), n - 1), min(max(c + dc, 0), n - 1)
    return r2 * n + c2


T = np.zeros((S, A, S))
for s in range(S):
    for a in range(A):
        for b in range(A):
            T[s, a, target(s, b)] += 0.9 if a == b else 0.1 / 3
corners = [0, n - 1, n * (n - 1), n * n - 1]
F = np.zeros((S, A, K))
for k, corner in enumerate(corners):
    F[corner, :, k] = 1.0
mdp = hbirl.Mdp(T, F, discount=0.95)
true_theta = np.array([0.0, 0.0, 0.0, 1.0])  # the expert wants the bottom-right corner
print(f"MDP: {mdp.num_states} states, {mdp.num_actions} actions, {mdp.num_features} features")

# %% [markdown]
# ## 2. The expert, the two people, the camera and the labeller
#
# The expert follows the MaxCausalEnt (soft) policy of its reward. The camera reports the
# cell of whoever it sees: the expert's own cell with probability 0.6, else a random
# cell. Person 1 wanders near the bottom-left corner, person 2 near the top-right. At each step the camera makes 6 detections, each
# of the expert with probability 0.3, else of one of the people; the labeller picks the
# true source 80% of the time and gives its pick 0.8 of η.

# %%
W, E, per_step, length = S, 2, 6, 10
subject_O = np.full((S, A, W), 0.4 / (W - 1))
for s in range(S):
    subject_O[s, :, s] = 0.6
person_O = np.zeros((E, W))
for e, corner in enumerate([corners[2], corners[1]]):
    cr, cc = divmod(corner, n)
    for w in range(W):
        r, c = divmod(w, n)
        person_O[e, w] = np.exp(-2 * (abs(r - cr) + abs(c - cc)))
person_O /= person_O.sum(axis=1, keepdims=True)
policy = mdp.soft_policy(true_theta)


def walk(trajectories):
    """Expert trajectories of `length` steps from the start distribution: (T, 2) arrays."""
    out = []
    for _ in range(trajectories):
        s, steps = rng.choice(S, p=mdp.start), []
        for _ in range(length):
            a = rng.choice(A, p=policy[s])
            steps.append((s, a))
            s = rng.choice(S, p=T[s, a])
        out.append(np.array(steps))
    return out


def watch(truth, alone=False):
    """What the camera and the labeller report of these trajectories: per step a pair
    (symbols, eta, context) with the labeller's pick as the context, and each
    observation's true source (0: the expert)."""
    trajectories, sources = [], []
    for steps in truth:
        trajectory = []
        for s, a in steps:
            z = np.zeros(per_step, dtype=int) if alone else np.where(rng.random(per_step) < 0.3, 0, rng.integers(1, E + 1, per_step))
            w = np.array([rng.choice(W, p=subject_O[s, a] if zi == 0 else person_O[zi - 1]) for zi in z])
            if alone:
                eta, pick = np.ones((per_step, 1)), np.zeros(per_step, dtype=int)  # the controlled run: only the expert
            else:
                other = (z + rng.integers(1, E + 1, per_step)) % (E + 1)  # one of the other sources
                pick = np.where(rng.random(per_step) < 0.8, z, other)
                eta = np.full((per_step, E + 1), 0.2 / E)
                eta[np.arange(per_step), pick] = 0.8
            trajectory.append((w, eta, pick))  # the pick is the labeller's rule: η's context
            sources.append(z)
        trajectories.append(trajectory)
    return trajectories, np.concatenate(sources)


demonstrations = walk(20)
observations, true_sources = watch(demonstrations)
print(f"{len(observations)} demonstrations, {len(true_sources)} observations, "
      f"{np.mean(true_sources == 0):.0%} of them the expert's")

# %% [markdown]
# ## 3. Learning with the hierarchical model
#
# The subject's observation prior comes from a controlled run: the expert alone for 10
# trajectories whose true cells are known (the paper's §Experiments), counted by
# `hbirl.controlled_run_prior`. The people's models start flat and are learned.

# %%
controlled = walk(10)
controlled_observations, _ = watch(controlled, alone=True)
prior = hbirl.ObservationPrior(mdp, num_symbols=W, num_confounders=E,
                               subject_alpha=hbirl.controlled_run_prior(mdp, controlled, controlled_observations, W))
model = hbirl.HierarchicalIRL().fit(mdp, observations, prior)
ile = hbirl.ile(mdp, true_theta, model.theta_)
print(f"HierarchicalIRL: theta {np.round(model.theta_, 2)}, ILE {ile:.3f} after {model.n_iter_} EM iterations")

# %% [markdown]
# ## 4. What EM did, where the expert went, what η really was
#
# `history_` holds the log-likelihood and θ at every EM iteration, so the inverse
# learning error (how much value the learned reward's optimal policy loses under the
# true reward) can be traced too. EM never lowers its objective while the subject
# prior's strength stands; once EM has converged that strength is chosen again from the
# data (held-out likelihood, docs/MODEL.md) and EM resumes on the new objective, where
# the likelihood may step down a little.
# `posterior` gives each step's `(S, A)` marginals and each observation's source
# posterior; `learned_eta_` the labeller's η per context (here its pick: the expert,
# person 1, person 2) as stated and as learned.

# %%
ile_per_iteration = [hbirl.ile(mdp, true_theta, theta) for theta in model.history_["theta"]]
marginals, source_posterior = model.posterior(observations)
believed_expert = source_posterior[:, 0] > 0.5
print(f"observations attributed right (expert or not): {np.mean(believed_expert == (true_sources == 0)):.0%}")
eta = model.learned_eta_
for c in range(len(eta["stated"])):
    print(f"context {c}: stated eta {np.round(eta['stated'][c], 2)}, learned {np.round(eta['learned'][c], 2)}")

# %% [markdown]
# ## 5. Against MaxCausalEnt on the true paths, and against ignoring the confounders
#
# MaxCausalEnt on the true trajectories is what a perfect tracker would allow. A learner
# that believes every detection is the expert's (η = the expert for all) shows what the
# confounders cost when they are ignored. The ILE judges a reward by its optimal policy
# alone, so it moves in steps: the first iterates, with θ still small, can already have
# the expert's optimal policy (ILE 0), and later ones trade a little value for avoiding
# corners the expert never visited.

# %%
truth_model = hbirl.MaxCausalEntIRL().fit(mdp, demonstrations)
truth_ile = hbirl.ile(mdp, true_theta, truth_model.theta_)
naive = [[(w, np.tile([1.0] + [0.0] * E, (len(w), 1))) for w, _, _ in trajectory] for trajectory in observations]
naive_model = hbirl.HierarchicalIRL(eta="stated").fit(mdp, naive, prior)
naive_ile = hbirl.ile(mdp, true_theta, naive_model.theta_)
print(f"ILE: hierarchical {ile:.3f}, MaxCausalEnt on the true paths {truth_ile:.3f}, "
      f"every observation taken as the expert's {naive_ile:.3f}")

# %% [markdown]
# ## The figure

# %%
fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
axes = axes.ravel()
iterations = np.arange(1, model.n_iter_ + 1)
ax = axes[0]
ax.plot(iterations, model.history_["log_likelihood"], marker=".", label="log-likelihood")
strength = model.history_["prior_strength"]
for i in np.flatnonzero(strength[1:] != strength[:-1]):
    ax.axvline(i + 1.5, color="grey", linestyle=":", label="subject prior's strength re-chosen" if i == np.flatnonzero(strength[1:] != strength[:-1])[0] else None)
ax.set_xlabel("EM iteration")
ax.set_ylabel("log Pr(observations | θ, O)")
ax.set_title("The likelihood during EM")
ax.legend(loc="lower right")
ax = axes[3]
ax.plot(iterations, ile_per_iteration, marker=".", label="HierarchicalIRL")
ax.axhline(truth_ile, color="green", linestyle="--", label="MaxCausalEnt, true paths")
ax.axhline(naive_ile, color="red", linestyle=":", label="confounders ignored")
ax.set_xlabel("EM iteration")
ax.set_ylabel("ILE (lower is better; log scale)")
ax.set_yscale("symlog", linthresh=0.1)
ax.set_title("Inverse learning error of each iterate")
ax.legend()
ax = axes[1]
state_marginals = marginals[0].sum(axis=2)  # (T, S): Pr(s_t = s | observations)
ax.imshow(state_marginals.T, aspect="auto", origin="lower", cmap="Blues", vmin=0, vmax=1)
ax.plot(np.arange(length), demonstrations[0][:, 0], "r.", markersize=10, label="true cell")
ax.set_xlabel("step")
ax.set_ylabel("cell (row * 5 + column)")
ax.set_title("Posterior over demonstration 0's cells")
ax.legend(loc="upper left")
ax = axes[2]
contexts = np.arange(len(eta["stated"]))
ax.bar(contexts - 0.2, eta["stated"][:, 0], width=0.4, label="stated")
ax.bar(contexts + 0.2, eta["learned"][:, 0], width=0.4, label="learned")
picks = np.concatenate([c for trajectory in observations for _, _, c in trajectory])
actual = [np.mean(true_sources[picks == c] == 0) for c in contexts]
ax.plot(contexts, actual, "k_", markersize=30, markeredgewidth=2, label="actual share")
ax.set_xticks(contexts, ["picks expert", "picks person 1", "picks person 2"])
ax.set_ylabel("η(expert)")
ax.set_title("The labeller's η, stated and learned")
ax.legend()
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"figure: {out}")
