"""hbirl for Python: inverse reinforcement learning in partially-controlled environments
(Bogert & Doshi, IROS 2021) with hbirl's C++ core, numpy in and out.

    import hbirl
    problem = hbirl.gridworld(size=5, confounders=3, seed=1)   # or hbirl.load_problem(path)
    model = hbirl.HierarchicalIRL().fit(problem.mdp, problem.observations(), problem.observation_prior)
    model.theta_, hbirl.ile(problem.mdp, problem.true_weights, model.theta_)

Shapes (S states, A actions, K features, W symbols, E confounding elements, J = 1 + E
sources, the subject first):
  Mdp: transitions (S, A, S) dense, a scipy.sparse (S*A, S) matrix, or (M, 4) rows
       [s, a, s', p]; features (S, A, K) dense or (M, 4) rows [s, a, k, value].
  policy (S, A); reward (S, A); soft values (S,); theta (K,).
  True trajectories: a list of (T, 2) integer arrays of (state, action).
  Observations: a list of trajectories, each a list of steps, each a pair (symbols (n,),
       eta (n, J)) or a triple with contexts (n,); or the flat form Observations(symbols
       (N,), eta (N, J), step_index (N,), lengths (trajectories,)) -- hmmlearn's `lengths`.
Bad input raises ValueError with the command line's one-line message, naming the
argument (docs/python.md "Python"). Every long call releases the GIL.
"""
import inspect
import json
import math
import os

import numpy as np

from . import _hbirl
from ._hbirl import Mdp, ObservationPrior, Problem, __version__, ile, load_domain, load_problem
from .sensor import Bus, Sensor
from . import msg

__all__ = [
    "Mdp", "ObservationPrior", "Observations", "Problem", "MaxCausalEntIRL", "HierarchicalIRL",
    "causal_log_likelihood", "controlled_run_prior", "gridworld", "ile", "load_domain", "load_problem", "onion", "read_log", "__version__",
    "Bus", "Sensor", "msg",
]


def _int_array(values, name):
    """An int64 array of whole numbers: floats such as 0.5 are refused, not truncated."""
    try:
        a = np.asarray(values)
    except ValueError:  # ragged
        raise ValueError(f"{name}: must be an array of integers") from None
    if a.dtype.kind not in "iuf":  # not bool, complex, dates or objects
        raise ValueError(f"{name}: must be an array of integers")
    if a.dtype.kind == "u" and a.size and a.max() >= 2 ** 63:
        raise ValueError(f"{name}: has values of 2^63 or more")
    if a.dtype.kind == "f":
        if a.size and not (np.all(np.isfinite(a)) and np.all(a == np.floor(a)) and np.all(np.abs(a) < 2.0 ** 62)):
            raise ValueError(f"{name}: must be whole numbers (got a fraction, inf or NaN)")
    return np.ascontiguousarray(a, dtype=np.int64)


def _int(value, name, low=-(2 ** 31), high=2 ** 31 - 1):
    """A whole number in [low, high], or ValueError naming it."""
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer, float, np.floating))
            or (isinstance(value, (float, np.floating)) and not math.isfinite(value)) or value != int(value)):
        raise ValueError(f"{name}: must be a whole number, got {value!r}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name}: must be in [{low}, {high}], got {value!r}")
    return int(value)


def _float(value, name):
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: must be a number, got {value!r}") from None


def causal_log_likelihood(mdp, trajectories, theta):
    """The causal log-likelihood L(theta) of true trajectories (a list of (T, 2) integer
    arrays of (state, action)) under the soft policy of theta, and its exact gradient
    (K,): what MaxCausalEntIRL maximises, for an optimiser of your own (docs/MODEL.md)."""
    return _hbirl.causal_log_likelihood(mdp, [_int_array(t, f"trajectories[{i}]") for i, t in enumerate(trajectories)],
                                        np.asarray(theta, dtype=np.float64))


class Observations:
    """Observations of demonstrations in the flat form (hmmlearn's `lengths`).

    symbols (N,) int: observation n's symbol, in [0, W).
    eta (N, J) float: its source distribution (rows sum to 1, the subject first).
    step_index (N,) int: the step it was made at, counting the steps of all trajectories in
        turn (nondecreasing): trajectory i's steps are sum(lengths[:i]) ... sum(lengths[:i+1]) - 1.
        A step without observations (occluded) simply has none.
    lengths (trajectories,) int: steps per trajectory.
    contexts (N,) int, optional: which rule of the labeller gave each eta (learned eta
        shares one source distribution per context; without them each distinct eta is one).
        -1 in every observation of a trajectory: that trajectory has none (with eta learned,
        every trajectory needs contexts or none does, as in a problem file).
    ends_in_terminal (trajectories,) bool, optional: the trajectory's last action led into a
        terminal state (rather than being cut off). Default as in a problem file: true when
        the MDP has terminal states.
    end_symbols (trajectories,) list of 1-D int arrays, optional: what an end sensor reported
        of the terminal state each trajectory's last action entered (docs/MODEL.md "Sensors
        that see the end"), symbols in [0, K) of the prior's num_end_symbols; an empty array:
        no report. Only for trajectories that end in a terminal state.
    end_state (trajectories,) int, optional: the terminal state each trajectory entered,
        when known for certain; -1: not known.
    """

    def __init__(self, symbols, eta, step_index, lengths, contexts=None, ends_in_terminal=None, end_symbols=None,
                 end_state=None):
        self.symbols = _int_array(symbols, "observations.symbols")
        try:
            self.eta = np.ascontiguousarray(eta, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("observations.eta: must be an (N, J) array of numbers") from None
        self.step_index = _int_array(step_index, "observations.step_index")
        self.lengths = _int_array(lengths, "observations.lengths")
        self.contexts = None if contexts is None else _int_array(contexts, "observations.contexts")
        self.ends_in_terminal = None if ends_in_terminal is None else [bool(x) for x in ends_in_terminal]
        self.end_symbols = _end_symbols(end_symbols)
        self.end_state = None if end_state is None else _int_array(end_state, "observations.end_state")

    @classmethod
    def from_list(cls, trajectories, ends_in_terminal=None, end_symbols=None, end_state=None):
        """From a list of trajectories, each a list of steps, each (symbols, eta) or
        (symbols, eta, contexts): symbols (n,), eta (n, J), contexts (n,); n may be 0.
        ends_in_terminal, end_symbols, end_state: as in Observations (the list form cannot
        carry them)."""
        if isinstance(trajectories, Observations):
            if ends_in_terminal is not None or end_symbols is not None or end_state is not None:
                raise ValueError("observations: an Observations already says how its trajectories ended; "
                                 "set its ends_in_terminal, end_symbols or end_state instead")
            return trajectories
        symbols, eta, steps, contexts, lengths = [], [], [], [], []
        sources = None  # columns of eta: from the first observation, else from an empty step's (0, J) eta
        with_contexts = None
        step = 0
        for i, trajectory in enumerate(trajectories):
            trajectory = list(trajectory)
            if not trajectory:
                raise ValueError(f"observations[{i}]: has no steps; a trajectory needs at least one")
            for t, item in enumerate(trajectory):
                where = f"observations[{i}][{t}]"
                if not isinstance(item, (tuple, list)) or len(item) not in (2, 3):
                    raise ValueError(f"{where}: a step is (symbols, eta) or (symbols, eta, contexts)")
                w = np.asarray(item[0])
                if w.ndim != 1:
                    raise ValueError(f"{where}: symbols must be a 1-D array")
                if w.size and not np.issubdtype(w.dtype, np.integer):
                    raise ValueError(f"{where}: symbols must be integers")
                try:
                    e = np.asarray(item[1], dtype=np.float64)
                except (TypeError, ValueError):
                    raise ValueError(f"{where}: eta must be an (n, J) array of numbers") from None
                if w.size == 0 and e.size == 0:
                    width = e.shape[1] if e.ndim == 2 else None
                    sources = sources or width
                    e = e.reshape(0, sources or 1)
                if e.ndim != 2 or e.shape[0] != w.size:
                    raise ValueError(f"{where}: eta must be an (n, J) array, one row per symbol")
                if w.size:
                    if sources is None:
                        sources = e.shape[1]
                    elif e.shape[1] != sources:
                        raise ValueError(f"{where}: eta has {e.shape[1]} columns, the earlier observations {sources}")
                    has = len(item) == 3
                    if with_contexts is None:
                        with_contexts = has
                    elif has != with_contexts:
                        raise ValueError(f"{where}: contexts are given for all observations or for none")
                    if has:
                        c = _int_array(item[2], f"{where}: contexts")
                        if c.shape != w.shape:
                            raise ValueError(f"{where}: contexts must have one entry per symbol")
                        contexts.append(c)
                    symbols.append(w.astype(np.int64))
                    eta.append(e)
                    steps.append(np.full(w.size, step, dtype=np.int64))
                step += 1
            lengths.append(len(trajectory))
        if not lengths:
            raise ValueError("observations: none given")
        cat = (lambda parts, dtype: np.concatenate(parts) if parts else np.zeros(0, dtype=dtype))
        return cls(
            cat(symbols, np.int64),
            np.concatenate(eta) if eta else np.zeros((0, sources or 1)),
            cat(steps, np.int64),
            np.asarray(lengths, dtype=np.int64),
            cat(contexts, np.int64) if with_contexts else None,
            ends_in_terminal,
            end_symbols,
            end_state,
        )

    def to_list(self):
        """The list form: trajectories of steps of (symbols, eta[, contexts]); it cannot
        carry ends_in_terminal, end_symbols or end_state (keep this object, or pass them to
        from_list)."""
        out = []
        first = 0
        for length in self.lengths:
            trajectory = []
            for step in range(first, first + int(length)):
                lo, hi = np.searchsorted(self.step_index, [step, step + 1])
                item = (self.symbols[lo:hi], self.eta[lo:hi])
                if self.contexts is not None:
                    item += (self.contexts[lo:hi],)
                trajectory.append(item)
            out.append(trajectory)
            first += int(length)
        return out

    def __len__(self):
        return len(self.lengths)

    def __repr__(self):
        return f"Observations({len(self)} trajectories, {int(self.lengths.sum())} steps, {self.symbols.size} observations)"

    def _tuple(self):
        # Checked again here: the attributes are public, and may have been changed since.
        return (_int_array(self.symbols, "observations.symbols"), np.ascontiguousarray(self.eta, dtype=np.float64),
                _int_array(self.step_index, "observations.step_index"), _int_array(self.lengths, "observations.lengths"),
                None if self.contexts is None else _int_array(self.contexts, "observations.contexts"),
                None if self.ends_in_terminal is None else [bool(x) for x in self.ends_in_terminal],
                _end_symbols(self.end_symbols),
                None if self.end_state is None else _int_array(self.end_state, "observations.end_state"))

    @classmethod
    def _of(cls, parts):
        return cls(*parts)


_MAX_END_REPORTS = _hbirl._MAX_END_REPORTS


def _end_symbols(end_symbols):
    """Each trajectory's end reports as a 1-D int array (None: no end sensor)."""
    if end_symbols is None:
        return None
    if isinstance(end_symbols, (str, bytes)):
        raise ValueError("observations.end_symbols: must be a list, one array of reports per trajectory")
    try:
        items = list(end_symbols)
    except TypeError:
        raise ValueError("observations.end_symbols: must be a list, one array of reports per trajectory") from None
    for i, r in enumerate(items):  # bounded before anything is converted (the C++ side checks each again)
        if hasattr(r, "__len__") and len(r) > _MAX_END_REPORTS:
            raise ValueError(f"observations.end_symbols[{i}]: has {len(r)} reports, more than the "
                             f"{_MAX_END_REPORTS} one ending may have")
    return [_int_array(r, f"observations.end_symbols[{i}]") for i, r in enumerate(items)]


def _as_observations(observations):
    if isinstance(observations, Observations):
        return observations
    if isinstance(observations, tuple) and 4 <= len(observations) <= 6 and all(
            isinstance(x, np.ndarray) or x is None for x in observations):
        return Observations(*observations)
    return Observations.from_list(observations)


def _problem_observations(self):
    """The demonstrations' observations (the controlled run's left out), as `hbirl learn`
    learns from them."""
    return Observations._of(self._observations())


Problem.observations = _problem_observations


def controlled_run_prior(mdp, truth, observations, num_symbols):
    """The subject's Dirichlet prior from a controlled run (paper §Experiments): symbol
    counts per (s, a) plus one, from the run's true steps (a list of (T, 2) arrays) and its
    observations (the subject alone: eta (n, 1) of ones). Returns an (S, A, W) array for
    ObservationPrior(subject_alpha=...)."""
    alpha = _hbirl.controlled_run_prior(mdp, [_int_array(t, f"truth[{i}]") for i, t in enumerate(truth)],
                                        _as_observations(observations)._tuple(), _int(num_symbols, "num_symbols"))
    return alpha.reshape(mdp.num_states, mdp.num_actions, alpha.shape[1])


def gridworld(size=5, trajectories=20, length=10, goal=None, goal_weight=1.0, intended=0.9, discount=0.95, seed=1,
              confounders=None, per_step=40, labeller_mass=0.8, labeller_accuracy=0.8, controlled=20):
    """The paper's Gridworld (§Experiments A) as a Problem, exactly as `hbirl generate
    gridworld` makes it from the same seed: size x size cells, moves that succeed with
    probability `intended`, a goal corner (0 top-left ... 3 bottom-right; None: drawn from
    the seed) of weight goal_weight, and `trajectories` demonstrations of `length` steps by
    the soft expert. With `confounders` (|E|) the demonstrations are watched through the
    paper's sensor: per_step observations per step, eta from a labeller that gives its
    pick labeller_mass but picks the true source with probability labeller_accuracy (its
    pick is each observation's context), and a controlled run of `controlled` trajectories
    for the subject prior (Problem.observation_prior)."""
    o = _hbirl._GridworldOptions()
    o.size, o.trajectories, o.length = _int(size, "size"), _int(trajectories, "trajectories"), _int(length, "length")
    o.goal = -1 if goal is None else _int(goal, "goal")
    o.goal_weight, o.intended = _float(goal_weight, "goal_weight"), _float(intended, "intended")
    o.discount, o.seed = _float(discount, "discount"), _int(seed, "seed", 0, 2 ** 64 - 1)
    o.confounders = -1 if confounders is None else _int(confounders, "confounders")
    o.per_step, o.controlled = _int(per_step, "per_step"), _int(controlled, "controlled")
    o.labeller_mass, o.labeller_accuracy = _float(labeller_mass, "labeller_mass"), _float(labeller_accuracy, "labeller_accuracy")
    return _hbirl.gridworld(o)


def onion():
    """The onion sorter (paper §Experiments B) as a Problem: its MDP, names and the
    expert's weights (no demonstrations: a run of the service set makes them)."""
    return _hbirl.onion()


def read_log(path, key=None, domain=None, allow_incomplete=False, eta=None):
    """A recorded run of the service set (lcm-logger, services/launch.sh --record) as a
    Problem: the domain's MDP and names, the demonstrations as the optimiser received them
    and the observation prior it learned from -- the data set `hbirl learn --log` uses and
    `hbirl export` writes, read here in process (so HierarchicalIRL().fit(p.mdp,
    p.observations(), p.observation_prior) gives the live run's theta). key: the run's key
    file for a signed run; domain: the domain file of a run on one; allow_incomplete: a run
    cut short, from its finished episodes; eta: "stated" or "learned", as the run's
    hbirl-optimiser --eta when given. A log that cannot be read raises ValueError with
    hbirl's one-line message."""
    return _hbirl._read_log(os.fspath(path), None if key is None else os.fspath(key),
                            None if domain is None else os.fspath(domain), bool(allow_incomplete),
                            None if eta is None else str(eta))


# Every learning setting, as `hbirl learn` has it (app/learn_settings.hpp): the estimators'
# keyword arguments, defaults and docstrings are made from this one schema.
_SETTINGS = {s["name"]: s for s in _hbirl._learn_settings()}


def _setting_value(name, value):
    """A keyword argument as the C++ schema takes it: whole numbers as int, numbers as float,
    choices as str, switches as bool; None where unset is allowed. The schema checks ranges."""
    s = _SETTINGS[name]
    if value is None:
        return None
    if s["type"] == "integer":
        return _int(value, name, s["min"], s["max"])
    if s["type"] == "number":
        return _float(value, name)
    if s["type"] == "switch":
        if not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"{name}: must be True, False or None, got {value!r}")
        return bool(value)
    if not isinstance(value, str):
        raise ValueError(f"{name}: must be {s['range']}, got {value!r}")
    return value


def _settings_doc(names):
    """The Parameters section of an estimator's docstring, from the schema."""
    lines = ["Parameters (as `hbirl learn`'s options of the same names):"]
    for name in names:
        s = _SETTINGS[name]
        default = s["unset"] if s["default"] is None else repr(s["default"])
        lines.append(f"  {name}: {s['help']} ({s['range']}; default {default}).")
    return "\n".join(lines)


def _with_settings(names):
    """A class decorator: an __init__ taking `names` as keyword arguments with the schema's
    defaults (what inspect.signature, get_params and set_params see), and the docstring's
    Parameters section."""
    parameters = [inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    parameters += [inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=_SETTINGS[n]["default"]) for n in names]
    signature = inspect.Signature(parameters)

    def __init__(self, **kwargs):
        bound = signature.bind(self, **kwargs)
        bound.apply_defaults()
        for name in names:
            setattr(self, name, bound.arguments[name])

    __init__.__signature__ = signature

    def decorate(cls):
        cls.__init__ = __init__
        cls.__doc__ = cls.__doc__.replace("{parameters}", _settings_doc(names))
        return cls

    return decorate


class _Estimator:
    """scikit-learn conventions: hyper-parameters in the constructor, get_params/set_params,
    fit returns self, fitted attributes end in "_"."""

    @classmethod
    def _param_names(cls):
        return [p for p in inspect.signature(cls.__init__).parameters if p != "self"]

    def get_params(self, deep=True):
        """The constructor's parameters, as a dict."""
        return {name: getattr(self, name) for name in self._param_names()}

    def set_params(self, **params):
        """Set constructor parameters; returns self."""
        names = self._param_names()
        for name, value in params.items():
            if name not in names:
                raise ValueError(f"{name}: not a parameter of {type(self).__name__} ({', '.join(names)})")
            setattr(self, name, value)
        return self

    def _settings(self):
        """The parameters as the C++ learner takes them (checked against the schema there)."""
        return {name: _setting_value(name, value) for name, value in self.get_params().items()}

    def __repr__(self):
        return type(self).__name__ + "(" + ", ".join(f"{k}={v!r}" for k, v in self.get_params().items()) + ")"

    def _check_fitted(self):
        if not hasattr(self, "theta_"):
            raise ValueError(f"{type(self).__name__}: not fitted yet; call fit first")


@_with_settings([name for name, s in _SETTINGS.items() if not s["observations_only"]])
class MaxCausalEntIRL(_Estimator):
    """Maximum causal entropy IRL from the expert's true steps (Ziebart et al.), as
    `hbirl learn --from truth` computes it: the same C++ function and the same settings, so
    the same theta bit for bit.

    {parameters}

    Fitted attributes: theta_ (K,), policy_ (S, A) the soft policy of theta_,
    log_likelihood_ (the causal log-likelihood of the demonstrations), posterior_ (None
    unless posterior_samples > 0: what the posterior over theta says, the dict `hbirl
    learn` prints as "posterior").
    """

    def fit(self, mdp, trajectories):
        """Learn reward weights from true trajectories, a list of (T, 2) integer arrays of
        (state, action). Returns self."""
        result = _hbirl._fit_maxcausalent(mdp, [_int_array(t, f"trajectories[{i}]") for i, t in enumerate(trajectories)],
                                          self._settings())
        self.theta_ = result["theta"]
        self.log_likelihood_ = result["log_likelihood"]
        self.policy_ = mdp.soft_policy(self.theta_)
        self.posterior_ = None if result["posterior"] is None else json.loads(result["posterior"])
        return self


@_with_settings(list(_SETTINGS))
class HierarchicalIRL(_Estimator):
    """The hierarchical Bayesian model of IRL in partially-controlled environments (Bogert &
    Doshi, IROS 2021): HiddenDataEM over the expert's unseen trajectories with the source of
    every observation summed out, the observation model (and eta) learned, MaxCausalEnt
    in the M-step -- as `hbirl learn --problem` runs it: the same C++ function and settings,
    so the same theta bit for bit.

    {parameters}

    Fitted attributes: theta_ (K,), policy_ (S, A), log_likelihood_, n_iter_ (EM iterates),
    converged_, history_ (dict of per-iterate arrays: "log_likelihood", "objective" (EM's:
    the log-likelihood plus the priors' terms; it never decreases while the subject prior's
    strength stands), "prior_strength" (that strength, chosen from the data between EM
    runs, docs/MODEL.md; NaN unless O is learned by the posterior update), "theta"
    (n_iter_, K)), observation_model_ (dict: "subject" (S, A, W), "confounders"
    (E', W), "end" (S, K) the end sensor's O_end over terminal states or None, the
    Dirichlet mean of the learned parameters; E' counts the unlisted catch-all when the
    prior asks for one), prior_ (the learned Dirichlet parameters, an
    ObservationPrior), learned_eta_ (None, or dict: per context "stated" (C, J'),
    "learned" (C, J'), "observations" (C,)), mcmc_diagnostics_ (MCMC only: worst R-hat and
    bulk ESS over the pair marginals), posterior_ (None unless posterior_samples > 0: what
    the posterior over theta says -- "confidence", credible intervals and more, the dict
    `hbirl learn` prints as "posterior").
    """

    def fit(self, mdp, observations, prior):
        """Learn the expert's reward from observations (a list of trajectories of steps of
        (symbols, eta[, contexts]), or Observations) and the observation model's prior (an
        ObservationPrior; Problem.observation_prior for a problem file). Returns self."""
        if not isinstance(prior, ObservationPrior):
            raise ValueError("prior: must be an hbirl.ObservationPrior")
        fit = _hbirl._fit_hierarchical(mdp, _as_observations(observations)._tuple(), prior, self._settings())
        self._fit = fit
        self.mdp_ = mdp
        self.theta_ = fit.theta
        self.policy_ = mdp.soft_policy(fit.theta)
        self.log_likelihood_ = fit.log_likelihood
        self.n_iter_ = fit.em_iterations
        self.converged_ = fit.converged
        self.history_ = {
            "log_likelihood": np.asarray(fit.history_log_likelihood),
            "objective": np.asarray(fit.history_objective),
            "prior_strength": np.asarray(fit.history_prior_strength),
            "theta": fit.history_theta,
        }
        subject = fit.subject
        self.observation_model_ = {
            "subject": subject.reshape(mdp.num_states, mdp.num_actions, subject.shape[1]),
            "confounders": fit.confounders,
            "end": fit.end,
        }
        self.prior_ = fit.refined
        self.learned_eta_ = fit.learned_eta
        self.mcmc_diagnostics_ = fit.mcmc_diagnostics
        self.posterior_ = None if fit.posterior is None else json.loads(fit.posterior)
        return self

    def score(self, observations):
        """log Pr(observations | theta_, O), exact, summed over trajectories (with learned
        eta, each observation's context's learned eta; contexts not seen in fit keep their
        stated eta). -inf when some trajectory is impossible under the model."""
        self._check_fitted()
        return float(np.sum(_hbirl._log_likelihoods(self.mdp_, self._fit, _as_observations(observations)._tuple())))

    def posterior(self, observations):
        """The posterior of each trajectory under theta_ and the learned model, by the
        fitted engine: (marginals, sources) with marginals a list of (T, S, A) arrays
        Pr(s_t = s, a_t = a | observations) and sources an (N, J') array, per observation
        in the flat order, Pr(source | observations), the subject first."""
        self._check_fitted()
        marginals, sources, _ = _hbirl._posterior(self.mdp_, self._fit, _as_observations(observations)._tuple())
        return marginals, sources

    def predict(self, observations):
        """The most likely (state, action) at every step (the argmax of each step's
        posterior marginal), a list of (T, 2) integer arrays."""
        marginals, _ = self.posterior(observations)
        out = []
        for m in marginals:
            flat = m.reshape(m.shape[0], -1).argmax(axis=1)
            out.append(np.stack([flat // m.shape[2], flat % m.shape[2]], axis=1).astype(np.int64))
        return out
