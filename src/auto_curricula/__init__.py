"""Automatic curricula of the field as mediated-transfer plugins, built through the same door a
user's strategy comes through (``_target_`` classes and ``conf/strategy/*.yaml`` on the config
search path: ``hydra.searchpath=[pkg://auto_curricula.conf]``), using only the public strategy
API (``mediated_transfer.transfer``: StrategyContext, EpisodeOutcome, the task space).

- ``dr``: domain randomisation over the target distance, source to target tasks, no feedback.
- ``reverse``: a reverse curriculum after Florensa et al. 2017: starts outward from the goal,
  kept while their success rate lies in [R_min, R_max], new starts by Brownian motion.
- ``plr``: Prioritized Level Replay (Jiang et al. 2021) over C and the target task, scored by
  the learner's TD errors, with staleness.
- ``learnability``: a success-based sampler over C and the target task, p(1 - p) (Sampling For
  Learnability, Rutherford et al. 2024, the sampler Kinetix trained with).

The study that compares them with the paper's scaffolding: conf/experiment/curricula.yaml,
reports/CURRICULA.md (``make curricula``); docs/curricula.md.
"""
