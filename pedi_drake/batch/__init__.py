"""Batch studies: many runs of missions or prong designs, on Ray or in one process.

    python -m pedi_drake.batch studies/friction_robustness.yaml            # local Ray, every core
    python -m pedi_drake.batch STUDY.yaml --address ray://head:10001       # the same on a cluster
    python -m pedi_drake.batch STUDY.yaml --engine serial                  # one process, for debugging

A study file (`study.py`) says what varies; each task builds and runs its own diagram and
returns a row (`tasks.py`); rows are appended as tasks finish (`results_file.py`), so an
interrupted study keeps them and `--resume` runs only what is missing; `summary.py` tabulates
and plots success and errors against each factor.
"""
