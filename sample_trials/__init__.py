"""Bundled synthetic sample trials (data only; see README.md here)."""
