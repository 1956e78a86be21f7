"""The command line, one module per command (nnik.cli registers them)."""
