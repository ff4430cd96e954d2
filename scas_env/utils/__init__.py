"""Plumbing every layer may use: atomic files, configuration files (TOML, YAML, JSON),
checked tables and shipped files, results folders, deterministic fan-out over worker
processes. Imports nothing of the project."""
