"""mediated-transfer: skill transfer for mediated interaction learning, reproduced.

Importing the package registers the environment ``mediated_transfer/MediatedInteraction-v0``.
"""

from .env import ENV_ID  # noqa: F401  (registers the Gymnasium environment)

__version__ = "0.1.0"
