"""One-off measurements behind figures and tables in the docs (not installed).

Each module is runnable (``python -m experiments.<name> --help``) and names the page and
the figure it backs."""
