"""muscles stage family."""
