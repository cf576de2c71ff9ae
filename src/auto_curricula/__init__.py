"""Automatic curricula of the field as mediated-transfer plugins, built through the same door a
user's strategy comes through (``_target_`` classes and ``conf/strategy/*.yaml`` on the config
search path: ``hydra.searchpath=[pkg://auto_curricula.conf]``), using only the public strategy
API (``mediated_transfer.transfer``: StrategyContext, EpisodeOutcome, the task space).

Each in the setting its own paper assumes (issue 42's study, conf/experiment/curricula2.yaml):
- ``dr``: domain randomisation over the target distance, the whole task space, no feedback.
- ``reverse``: a reverse curriculum after Florensa et al. 2017: starts outward from the goal,
  kept while their success rate lies in [R_min, R_max], new starts by short random walks.
- ``plr_annulus``: Prioritized Level Replay (Jiang et al. 2021) over C and a fixed set of
  target-task levels, scored by the learner's TD errors, with staleness.
- ``sfl``: Sampling For Learnability (Rutherford et al. 2024) with its generator: fresh levels
  over the whole task space, a buffer of the highest p (1 - p) rebuilt from each scored batch.
- ``alp_gmm``: ALP-GMM (Portelas et al. 2019): Gaussian mixtures over (distance, learning
  progress), 20 % of tasks uniform.
- ``currot``: CURROT (Klink et al. 2022): particles moved from the source distances toward the
  target annulus by optimal transport, under a success constraint and a trust region.
- ``plr_handover``, ``learnability_handover``: feedback curricula as orderings of C under the
  paper's hand-over rule (target tasks once every task of C was solved).
The first study's ``plr`` and ``learnability`` (over C and one target level) stay as its runs
computed them.

The study: conf/experiment/curricula2.yaml, reports/CURRICULA.md (``make curricula``);
docs/curricula.md.
"""
