"""Plumbing every layer may use: atomic files, checked tables and shipped files, results
folders, deterministic fan-out over worker processes. Imports nothing of the project."""
