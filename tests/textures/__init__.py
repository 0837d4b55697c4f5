"""One test file per texture plugin (test_<name>.py, as clrender/textures/<name>.py and kernels/textures/<name>.h)."""
