"""Issue 13's sensitivity study: how the gain from transfer depends on the task.

The study itself is config (conf/experiment/sensitivity.yaml, pre-registered): one world
(conf/env/ option) per reading of the paper's open geometry, each x {none, regular N=50,
scaffolded N=50} x 10 seeds. Its runs are an ordinary sweep; this package only reads them.

- ``study``: the worlds, arms and seeds of the study, and where their runs are;
- ``measures``: per world, discovery rarity, post-discovery learning, and the gains with
  bootstrap confidence intervals;
- ``report``: reports/SENSITIVITY.md, its table and figure (``python -m mediated_transfer.sensitivity``).
"""
