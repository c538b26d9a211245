"""This user's private folders on this machine, and the shape of a launch's session id (below every layer).

Everything hetros keeps between processes of one user (the launch registry, each launch's
folder, iceoryx2's node and service records) lives under one base folder:
``$XDG_RUNTIME_DIR/hetros`` where the login manager gives the user a private runtime folder,
else ``/tmp/hetros-<uid>``. ``/tmp`` is shared by every account, so another one may have
made that name first (a squat), or made it a link to a folder of the victim's: each folder is
checked (a real folder, not a link, owned by this user) before anything is read from or
written into it, and refused with the fix named otherwise. Nothing machine-wide is shared
between accounts, so one user's crashed launch cannot lock another out.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

from ._errors import MachineError

# what ``transport.new_session`` makes: ``<pid>x<tag><6 hex digits>``; a record or a folder
# name of any other shape is not one of ours, and nothing is removed by it
SESSION_PATTERN = re.compile(r"[1-9][0-9]{0,9}x[a-wyz0-9]{6,22}")


def is_session(name: object) -> bool:
    """Whether ``name`` has the shape of a launch's session id (and so names nothing but one)."""
    return isinstance(name, str) and SESSION_PATTERN.fullmatch(name) is not None


def check_session(name: object) -> str:
    if not is_session(name):
        raise MachineError(f"a launch's session id must look like <pid>x<letters and digits>, not {name!r}: "
                           "it names a folder hetros may remove, so nothing else is accepted")
    assert isinstance(name, str)
    return name


def private_folder(path: Path) -> Path:
    """``path`` as a folder of this user's only (made with mode 0700 when missing).

    Refused when it is a link or anything but a folder, or belongs to another account; a
    folder of ours that others may enter is closed to them.
    """
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError as exc:
        raise MachineError(f"cannot make hetros's private folder {path}: {exc.strerror}; set XDG_RUNTIME_DIR "
                           "to a folder of yours that exists") from exc
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        kind = "a link" if stat.S_ISLNK(info.st_mode) else "not a folder"
        raise MachineError(f"{path} is {kind}, where hetros keeps this user's private files: someone may be trying "
                           f"to redirect them; remove it (`rm {path}`), or set XDG_RUNTIME_DIR to a folder of yours")
    if info.st_uid != os.getuid():
        raise MachineError(f"{path} belongs to user {info.st_uid}, not to you ({os.getuid()}): hetros keeps your "
                           "private files there, so it will not use it; ask its owner or root to remove it, or set "
                           "XDG_RUNTIME_DIR to a folder of yours")
    if stat.S_IMODE(info.st_mode) & 0o077:
        os.chmod(path, 0o700)
    return path


def user_folder(max_length: int | None = None) -> Path:
    """The base of this user's hetros files (checked; see the module's docstring).

    ``max_length``: a base whose path is longer (a deep ``XDG_RUNTIME_DIR``) gives way to
    ``/tmp/hetros-<uid>``, for files whose full path must stay short (a Unix socket's, 107 bytes).
    """
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and (max_length is None or len(os.path.join(runtime, "hetros")) <= max_length):
        base = Path(runtime)
        try:
            owner = os.stat(base).st_uid
        except OSError as exc:
            raise MachineError(f"XDG_RUNTIME_DIR names {base}, which cannot be used ({exc.strerror}): point it at "
                               "a folder of yours, or unset it") from exc
        if owner != os.getuid():
            raise MachineError(f"XDG_RUNTIME_DIR names {base}, which belongs to user {owner}, not to you "
                               f"({os.getuid()}): point it at a folder of yours, or unset it")
        return private_folder(base / "hetros")
    return private_folder(Path("/tmp") / f"hetros-{os.getuid()}")


def user_subfolder(*names: str, max_length: int | None = None) -> Path:
    """A private folder under :func:`user_folder` (each level checked)."""
    folder = user_folder(max_length)
    for name in names:
        folder = private_folder(folder / name)
    return folder


__all__ = ["SESSION_PATTERN", "check_session", "is_session", "private_folder", "user_folder", "user_subfolder"]
