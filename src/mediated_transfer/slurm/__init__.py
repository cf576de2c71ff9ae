"""The SLURM launcher's parts (the launcher itself is hydra_plugins.mediated_transfer_launcher,
where Hydra requires a launcher to live): which runs to submit and how to group them (jobs),
what the cluster allows (cluster), one-line errors (errors), waiting with progress (watch) and
the record of submitted jobs that a rerun attaches to (ledger)."""
