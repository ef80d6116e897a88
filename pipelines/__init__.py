"""Bundled pipeline YAML files (data only)."""
