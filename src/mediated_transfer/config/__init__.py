"""Configuration: the schema Hydra validates conf/ against, composing a config from overrides
with one-line errors, and turning a composed config into a RunSpec.

Modules are imported one by one (``from mediated_transfer.config.compose import ...``): the
schema imports every learner (torch among them), which the environment must not pay for.
"""
