"""The paper's lab work (not installed): [DJS20] sections 4-5 reproduced from this package's
physics, its physics figures, the Monte Carlo campaigns behind them and the demonstration
runs. docs/reproduction.md reports the results.

Commands (``python -m experiments.paper.<name> --help``; docs/cli.md shows each one's help):

* ``reproduce``: the reproduction (campaign, selection, detection, prognosis, report);
* ``campaign``: a Monte Carlo campaign of the physics model, saved as a feature table;
* ``figures``: the paper's physics figures (Figs. 3, 4, 5, 7a, 7b);
* ``demo``: the actuator at three health states, signals as CSV and PNG;
* ``reproduction_detection``: severity at detection with an installation baseline;
* ``reproduction_presets``: the reproduction's verdicts side by side, one column per
  sensing preset.

Libraries: ``campaign_table`` (the campaign's files), ``reproduction``,
``reproduction_prognosis``, ``reproduction_conventions``, ``reproduction_report``,
``figure_data``.
"""
