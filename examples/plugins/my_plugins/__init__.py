"""A researcher's own package beside mediated-transfer: a strategy, a learner and a world
variant, each one Python file (or none) and one YAML under conf/ (docs/extending.md)."""
