"""mediated-transfer: skill transfer for mediated interaction learning, reproduced."""

__version__ = "0.1.0"
