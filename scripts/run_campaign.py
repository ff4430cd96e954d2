"""Monte Carlo campaign: ``scas-campaign`` (options: ``--help``, docs/cli.md)."""

from scas_env.studies.cli import campaign_main

if __name__ == "__main__":
    raise SystemExit(campaign_main())
