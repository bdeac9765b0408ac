"""weld."""
