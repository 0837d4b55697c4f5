"""One test file per emitter plugin (test_<name>.py, as clrender/emitters/<name>.py and kernels/emitters/<name>.h)."""
