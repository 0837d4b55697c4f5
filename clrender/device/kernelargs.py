"""Setting a kernel's arguments by the names its source gives them, never by position.

Programs are built with -cl-kernel-arg-info (clrender/device/program.py), so the driver reports each argument's
name; the scene's tables are the arguments s_<table> of SCENE_ARGS (clrender/device/layout.py SCENE_TABLES).
"""
from __future__ import annotations


class KernelArgs:
    """Note: like pyopencl's set_arg, this keeps no reference to the buffers it sets: keep them alive."""

    def __init__(self, kernel):
        import pyopencl as cl

        self.kernel = kernel
        self.index = {kernel.get_arg_info(i, cl.kernel_arg_info.NAME): i for i in range(kernel.num_args)}

    def set(self, **values) -> "KernelArgs":
        for name, value in values.items():
            try:
                i = self.index[name]
            except KeyError:
                raise KeyError(f"kernel {self.kernel.function_name} has no argument {name!r}; it takes "
                               f"{', '.join(self.index)}") from None
            self.kernel.set_arg(i, value)
        return self

    def set_scene(self, tables: dict) -> "KernelArgs":
        """The scene's device buffers, {table name: buffer}, as the arguments s_<name>."""
        return self.set(**{f"s_{name}": buf for name, buf in tables.items()})

    def names(self) -> list[str]:
        return list(self.index)
