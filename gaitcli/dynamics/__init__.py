"""dynamics stage family."""
