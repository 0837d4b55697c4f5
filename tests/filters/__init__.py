"""One test file per reconstruction filter plugin (test_<name>.py, as clrender/filters/<name>.py)."""
