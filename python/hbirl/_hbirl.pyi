# Type stubs of the extension module (python/src/module.cpp).
from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

class Mdp:
    def __init__(
        self,
        transitions: npt.ArrayLike,  # (S, A, S)
        features: npt.ArrayLike,  # (S, A, K)
        start: Optional[npt.ArrayLike] = ...,  # (S,)
        terminal: Sequence[int] = ...,
        discount: float = ...,
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
    def reward(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S, A)
    def soft_policy(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S, A)
    def soft_values(self, theta: npt.ArrayLike) -> np.ndarray: ...  # (S,)

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
    def truth_trajectories(self) -> list[np.ndarray]: ...  # each (T, 2) of (state, action)

def ile(mdp: Mdp, true_theta: npt.ArrayLike, learned_theta: npt.ArrayLike) -> float: ...
def load_problem(path: str) -> Problem: ...
def _fit_maxcausalent(
    mdp: Mdp,
    trajectories: Sequence[npt.ArrayLike],
    optimizer: str,
    l2: float,
    restarts: int,
    seed: int,
    max_iterations: int,
    tolerance: float,
    threads: int,
) -> dict: ...
