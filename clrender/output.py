"""Where `clrender render` writes, decided and checked before the scene is loaded.

Rules (README, "Command line"): no `-o`: SCENE.exr beside the scene. `-o NAME.exr`: that file. `-o NAME`
without an extension: NAME.exr. `-o FOLDER` (an existing folder, or a name ending in '/'): FOLDER/SCENE.exr.
An EXR gets a PNG preview beside it. `-o NAME.png|.jpg|.jpeg|.hdr|.pfm`: that file in that format, alone (the
user named the file they want). Any other extension is an error.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import ClrenderError

EXTENSION = ".exr"
#: the formats `-o NAME.ext` writes besides OpenEXR (Film.write)
IMAGE_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".hdr": "Radiance HDR", ".pfm": "PFM"}


def output_paths(option: str | None, scene: str, exr_only: str | None = None) -> tuple[Path, Path | None]:
    """(image path, path of its PNG preview or None) for `-o option` and the scene file, or a ClrenderError naming
    the option. `exr_only`: why only OpenEXR will do (said in the error), for writers of EXR alone."""
    scene_path = Path(scene)
    if option is None:
        exr = scene_path.with_suffix(EXTENSION)
    elif option == "":
        raise ClrenderError("-o: the output name is empty")
    else:
        p = Path(option)
        suffix = p.suffix.lower()
        if option.endswith(("/", os.sep)) or p.is_dir():
            exr = p / (scene_path.stem + EXTENSION)
        elif suffix == "":
            exr = p.with_name(p.name + EXTENSION)
        elif suffix == EXTENSION:
            exr = p
        elif suffix in IMAGE_FORMATS and not exr_only:
            check_writable(p, option)
            return p, None
        elif exr_only:
            raise ClrenderError(f"-o {option}: {exr_only}: the output must end in {EXTENSION}, have no extension, "
                                f"or name a folder (got '{p.suffix}')")
        else:
            raise ClrenderError(f"-o {option}: clrender writes OpenEXR (with a PNG preview beside it), "
                                f"{', '.join(dict.fromkeys(IMAGE_FORMATS.values()))}; the output must end in "
                                f"{', '.join((EXTENSION, *IMAGE_FORMATS))}, have no extension, or name a folder "
                                f"(got '{p.suffix}')")
    png = exr.with_suffix(".png")
    for path in (exr, png):
        check_writable(path, option)
    return exr, png


def check_writable(path: Path, option: str | None = None) -> None:
    """Fail now, naming the user's path, if `path` cannot be written (atomically, via its folder)."""
    said = f"-o {option}: " if option else ""
    if path.is_dir():
        raise ClrenderError(f"{said}cannot write '{path}': it is a folder")
    if path.exists() and not path.is_file():
        raise ClrenderError(f"{said}cannot write '{path}': it exists and is not a regular file")
    folder = path.parent
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ClrenderError(f"{said}cannot write '{path}': '{existing}' is not a folder")
    if existing != folder:  # the folders are created at write time; their parent must let us
        if not os.access(existing, os.W_OK | os.X_OK):
            raise ClrenderError(f"{said}cannot create the folder '{folder}': '{existing}' is not writable")
        return
    try:  # the write goes through a temporary file in the same folder: try exactly that
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".probe", dir=str(folder))
    except OSError as e:
        raise ClrenderError(f"{said}cannot write '{path}': {e.strerror or e}") from None
    os.close(fd)
    os.unlink(probe)
