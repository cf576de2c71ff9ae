"""Random search whose trial k draws the same values whoever runs it and whenever.

Optuna's RandomSampler(seed) draws from one stream per process: two workers with the same seed
would draw the same values, and a resumed study would repeat its first trials. Seeding a
RandomSampler per (study seed, trial number, key) makes each trial's values a function of its
number alone, so a study is reproducible across worker counts and resumptions.
"""

from __future__ import annotations

import zlib

import numpy as np
from optuna.samplers import BaseSampler, RandomSampler


class TrialSeededRandomSampler(BaseSampler):
    def __init__(self, seed: int):
        self.seed = int(seed)

    def infer_relative_search_space(self, study, trial):
        return {}

    def sample_relative(self, study, trial, search_space):
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        stream = np.random.SeedSequence([self.seed, trial.number, zlib.crc32(param_name.encode())])
        sampler = RandomSampler(seed=int(stream.generate_state(1)[0]))
        return sampler.sample_independent(study, trial, param_name, param_distribution)
