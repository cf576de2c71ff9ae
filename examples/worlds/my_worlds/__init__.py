"""A researcher's own worlds beside mediated-transfer, each one Python file and one YAML under
conf/env/ (docs/extending.md, "A world of one's own"): a rake and an extra sensor."""
