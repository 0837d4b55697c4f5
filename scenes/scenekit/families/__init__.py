"""One module per scene family: its constants, ``build_<family>(out)`` and ``check(out)`` (sanity checks)."""
