"""Command-line interface: ``switchobs <command> ...``."""
