"""One module per ``weldplan`` command (see weldplan.cli)."""
