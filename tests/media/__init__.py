"""One test file per participating medium plugin (test_<name>.py, as clrender/media/<name>.py and
kernels/media/<name>.h)."""
