"""Files of the output folder written whole or not at all.

Each is written to a hidden temporary file in the same folder (`.NAME.*.tmp`, created
exclusively with an unpredictable name, so a planted symlink is never followed) and renamed
over the target when complete: a kill leaves the old file or the new one, never a part.
A kill can leave the temporary file; the next sweep into the folder removes it.
"""

import os
import tempfile
from pathlib import Path

_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once: mkstemp makes files 0600, the rename should leave them as open() would


def write_atomic(path: Path, write):
    """Calls write(file) on a temporary file opened for binary writing, then renames it to `path`."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_bytes(path: Path, data: bytes):
    write_atomic(path, lambda f: f.write(data))


def remove_leftovers(folder: Path, names):
    """The temporary files that a killed sweep left in `folder` for the files `names`
    (glob patterns such as "*.fmu")."""
    for leftover in (p for name in names for p in Path(folder).glob(f".{name}.*.tmp")):
        if leftover.is_file() and not leftover.is_symlink():
            leftover.unlink(missing_ok=True)
