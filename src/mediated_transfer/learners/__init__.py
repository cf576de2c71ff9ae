"""The learners of section IV and their representations, behind one interface (base.Learner).

Linear Q(lambda) (Tables II and III) learns on the RBF or the FSR features; the deep
Q-learner (Table IV) lives in dqn.py.
"""

from .base import Learner
from .fsr import FSRConfig, FSRRepresentation
from .linear_q import LEARNING_RATE_DECAYS, LinearQConfig, LinearQLearner, boyan_rate
from .rbf import RBFConfig, RBFRepresentation

__all__ = [
    "Learner",
    "LinearQConfig", "LinearQLearner", "LEARNING_RATE_DECAYS", "boyan_rate",
    "RBFConfig", "RBFRepresentation",
    "FSRConfig", "FSRRepresentation",
]
