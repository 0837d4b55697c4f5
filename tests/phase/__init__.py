"""One test file per phase function plugin (test_<name>.py, as clrender/phase/<name>.py and kernels/phase/<name>.h)."""
