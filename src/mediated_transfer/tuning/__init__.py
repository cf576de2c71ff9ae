"""The paper's tuning protocol, run openly: Table I rebuilt (issue 9).

The paper tuned each learner "using random search ... so that the reward within the regular
learning runs without transfer learning is maximized". Here a search space per learner is config
(conf/hparams_search/), every trial is a set of runs without transfer at the paper's budget on
tuning seeds that are not the table seeds, and the objective is their mean reward loss L_R.
The provisional defaults are the first trial, so Table I compares them with the best on the same
seeds. Per seed a trial also records when the learner discovered the target task (its first
rewarded target-task episode) and how long it then took to learn it (to the first <R> >= 8).

Modules, one job each:
    space       load and check a search-space file
    objective   one trial: its runs, its reward loss and the discovery / learning split
    sampler     random search seeded per trial (reproducible across workers and resumptions)
    study       the Optuna study: storage, resumption, workers, progress
    mlflow_log  one MLflow run per trial, nested under the study's run
    export      trials.csv from the study, and a consistent copy of the study's database
    table1      reports/table1.md and its figures from the committed trials.csv files
"""
