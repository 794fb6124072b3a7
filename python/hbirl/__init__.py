"""hbirl for Python: inverse reinforcement learning with hbirl's C++ core, numpy in and out.

    import hbirl
    problem = hbirl.load_problem("examples/corridor.json")
    irl = hbirl.MaxCausalEntIRL().fit(problem.mdp, problem.truth_trajectories())
    irl.theta_, irl.policy_, hbirl.ile(problem.mdp, problem.true_weights, irl.theta_)

Shapes: an MDP's transitions are an (S, A, S) array, its features (S, A, K); a policy is
(S, A); a trajectory of true steps is a (T, 2) integer array of (state, action). Bad input
raises ValueError with the command line's one-line message (README.md "Python").
"""
from ._hbirl import Mdp, Problem, __version__, ile, load_problem

__all__ = ["Mdp", "Problem", "MaxCausalEntIRL", "ile", "load_problem", "__version__"]


class MaxCausalEntIRL:
    """Maximum causal entropy IRL from the expert's true steps (Ziebart et al.), as
    `hbirl learn --from truth` computes it: the same C++ code and the same defaults, so the
    same theta bit for bit.

    Parameters (scikit-learn style: set here, fitted attributes end in "_"):
      optimizer: "lbfgs" (default) or "eg" (exponentiated gradient on an L1 ball).
      l2: penalty on ||theta||^2 per demonstrated step (default 0).
      restarts: random restarts of the optimiser (default 1).
      seed: seed of the restarts.
      max_iterations, tolerance: the optimiser's budget and gradient tolerance.
      threads: 0 for one per core; the result does not depend on it.

    Fitted attributes: theta_ (K,), policy_ (S, A) the soft policy of theta_,
    log_likelihood_ (the causal log-likelihood of the demonstrations).
    """

    def __init__(self, optimizer="lbfgs", l2=0.0, restarts=1, seed=1, max_iterations=1000, tolerance=1e-9, threads=0):
        self.optimizer = optimizer
        self.l2 = l2
        self.restarts = restarts
        self.seed = seed
        self.max_iterations = max_iterations
        self.tolerance = tolerance
        self.threads = threads

    _params = ("optimizer", "l2", "restarts", "seed", "max_iterations", "tolerance", "threads")

    def get_params(self, deep=True):
        """The constructor's parameters, as a dict."""
        return {name: getattr(self, name) for name in self._params}

    def set_params(self, **params):
        """Set constructor parameters; returns self."""
        for name, value in params.items():
            if name not in self._params:
                raise ValueError(f"{name}: not a parameter of MaxCausalEntIRL ({', '.join(self._params)})")
            setattr(self, name, value)
        return self

    def fit(self, mdp, trajectories):
        """Learn reward weights from true trajectories, a list of (T, 2) integer arrays of
        (state, action). Releases the GIL while it computes. Returns self."""
        from . import _hbirl

        result = _hbirl._fit_maxcausalent(mdp, list(trajectories), self.optimizer, float(self.l2), int(self.restarts),
                                          int(self.seed), int(self.max_iterations), float(self.tolerance), int(self.threads))
        self.theta_ = result["theta"]
        self.log_likelihood_ = result["log_likelihood"]
        self.policy_ = mdp.soft_policy(self.theta_)
        return self

    def __repr__(self):
        return "MaxCausalEntIRL(" + ", ".join(f"{k}={v!r}" for k, v in self.get_params().items()) + ")"
