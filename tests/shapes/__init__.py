"""One test file per shape plugin (test_<name>.py, as clrender/shapes/<name>.py)."""
