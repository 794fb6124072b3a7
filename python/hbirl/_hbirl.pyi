# Type stubs of the extension module (python/src/module.cpp). Shapes: S states, A actions,
# K features, W symbols, E confounding elements, J = 1 + E sources.
from typing import Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

class Mdp:
    def __init__(
        self,
        transitions: object,  # (S, A, S) dense, scipy.sparse (S*A, S), or (M, 4) rows [s, a, s', p]
        features: npt.ArrayLike,  # (S, A, K) dense or (M, 4) rows [s, a, k, value]
        start: Optional[npt.ArrayLike] = ...,  # (S,)
        terminal: Sequence[int] = ...,
        discount: float = ...,
        impossible: Sequence[tuple[int, int]] = ...,
        num_states: Optional[int] = ...,
        num_actions: Optional[int] = ...,
        num_features: Optional[int] = ...,
    ) -> None: ...
    @property
    def num_states(self) -> int: ...
    @property
    def num_actions(self) -> int: ...
    @property
    def num_features(self) -> int: ...
    @property
    def discount(self) -> float: ...
    @property
    def start(self) -> np.ndarray: ...  # (S,)
    @property
    def terminal(self) -> list[int]: ...
    def transition_rows(self) -> np.ndarray: ...  # (M, 4)
    def reward(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S, A)
    def soft_policy(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S, A)
    def soft_values(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S,)
    def optimal_policy(self, reward: npt.ArrayLike) -> tuple[list[int], np.ndarray]: ...  # actions (S,), V* (S,)

class ObservationPrior:
    def __init__(
        self,
        mdp: Mdp,
        num_symbols: int,
        num_confounders: int,
        subject_alpha: Union[float, npt.ArrayLike] = ...,  # number or (S, A, W)
        confounder_alpha: Union[float, npt.ArrayLike] = ...,  # number or (E, W)
        subject_alpha_default: Optional[float] = ...,
        update: str = ...,  # "posterior" or "paper"
        c: float = ...,
        prior_strength: Union[str, float] = ...,  # "auto" or a number
        learn: Optional[bool] = ...,
        learn_eta: Optional[bool] = ...,
        eta_strength: float = ...,
        unlisted_eta: float = ...,
        num_end_symbols: int = ...,  # the end sensor's alphabet; 0: none
        end_alpha: Union[None, float, npt.ArrayLike] = ...,  # number (every terminal state; default 1) or (S, K)
        end_alpha_default: Optional[float] = ...,
        tie_actions: bool = ...,  # the subject's prior tied across each state's actions
    ) -> None: ...
    @property
    def num_symbols(self) -> int: ...
    @property
    def num_confounders(self) -> int: ...
    @property
    def confounder_alpha(self) -> np.ndarray: ...  # (E, W)
    @property
    def tie_actions(self) -> bool: ...
    @property
    def num_end_symbols(self) -> int: ...
    @property
    def end_alpha(self) -> Optional[np.ndarray]: ...  # (S, K), or None: no end sensor
    def subject_alpha(self, mdp: Mdp) -> np.ndarray: ...  # (S, A, W)
    @property
    def update(self) -> str: ...
    @property
    def learn(self) -> bool: ...
    @property
    def learn_eta(self) -> bool: ...
    @property
    def eta_strength(self) -> float: ...
    @property
    def unlisted_eta(self) -> float: ...
    @property
    def prior_strength(self) -> Union[str, float]: ...

class Problem:
    @property
    def mdp(self) -> Mdp: ...
    @property
    def feature_names(self) -> list[str]: ...
    @property
    def state_names(self) -> list[str]: ...
    @property
    def action_names(self) -> list[str]: ...
    @property
    def true_weights(self) -> Optional[np.ndarray]: ...
    @property
    def observation_prior(self) -> ObservationPrior: ...
    def truth_trajectories(self) -> list[np.ndarray]: ...  # each (T, 2) of (state, action)
    def observations(self) -> object: ...  # hbirl.Observations
    def save(self, path: str) -> None: ...

def causal_log_likelihood(
    mdp: Mdp, trajectories: Sequence[npt.ArrayLike], theta: npt.ArrayLike
) -> tuple[float, np.ndarray]: ...  # L(theta), dL/dtheta (K,)
def ile(mdp: Mdp, true_theta: npt.ArrayLike, learned_theta: npt.ArrayLike) -> float: ...
def load_problem(path: str) -> Problem: ...
def load_domain(path: str) -> Problem: ...
