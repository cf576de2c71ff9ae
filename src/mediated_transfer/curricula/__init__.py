"""The curricula study (issue 35; conf/experiment/curricula.yaml, pre-registered): the field's
automatic curricula (src/auto_curricula) against the paper's scaffolding, per linear learner.
``python -m mediated_transfer.curricula`` builds reports/CURRICULA.md from its runs."""
