"""predict stage family."""
