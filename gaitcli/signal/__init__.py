"""signal stage family."""
