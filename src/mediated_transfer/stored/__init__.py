"""A run's files as stored, and how they are judged when read back (results.py is their door).

- ``codec``: result.json's text: strict JSON, ``inf`` where a config key means it, a checksum.
- ``check``: reading a stored run validates it; a damaged one raises ``DamagedResult``, one
  line naming the file and what is wrong.
- ``aside``: a damaged run's files renamed, never deleted, so that a sweep can recompute it.

None of this is part of what a run computes, so none of it is in a result's code digest.
"""

RESULT_FILE = "result.json"
CURVE_FILE = "curve.csv"
CURVE_HEADER = "step,mean_reward,success_rate"
LINEAR_FILE = "learner.npz"
DQN_FILE = "learner.pt"
LEARNER_FILES = (LINEAR_FILE, DQN_FILE)
"""A run's trained learner (saved_learner.py): a linear learner's arrays, a torch learner's state."""
