"""`hexpipe sweep`: many training seeds and settings on Ray, reported with intervals.

grid.py (conditions x seeds -> trials and their Params) -> runner.py (Ray tasks, progress, resume) running
trial.py (train-ppo + evaluate for one trial) with records in store.py -> tables.py (episodes -> per-seed and
per-condition tables) using stats.py (the pure statistics) -> report.py (metrics.json, CSVs, report.md, figures).
run.py ties them together for the CLI.
"""
