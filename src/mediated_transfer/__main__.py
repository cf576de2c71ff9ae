"""``python -m mediated_transfer [overrides]``: one learning run; ``-m`` sweeps (see app.py)."""

from .app import cli

if __name__ == "__main__":
    cli()
