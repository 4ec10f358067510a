"""Test harness shared by several test files (not part of the library)."""
