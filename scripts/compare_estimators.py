"""UKF vs particle filter on the same simulated lives: calibration, sharpness and cost.

Options: ``--help`` and docs/estimators.md.
"""

from experiments.estimator_comparison import main

if __name__ == "__main__":
    raise SystemExit(main())
