"""One test file per BSDF plugin (test_<name>.py, as clrender/bsdfs/<name>.py and kernels/bsdfs/<name>.h)."""
