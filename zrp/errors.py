"""One exception hierarchy for the whole toolkit.

Every error raised on bad user input derives from :class:`ZRPError`, and from the matching
built-in (``ValueError``, ``FileExistsError``...) so that generic handlers keep working.
Messages name the field, joint, file line or option at fault and say what was expected.
"""

from __future__ import annotations

__all__ = [
    "IKError",
    "InputError",
    "JointLimitError",
    "ModelError",
    "ModelFileError",
    "OutputBusyError",
    "OutputExistsError",
    "OutputIsInputError",
    "OutputKindError",
    "SingularityError",
    "SingularityWarning",
    "TrackingWarning",
    "UnitError",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
]


class ZRPError(Exception):
    """Base class of every error raised by this toolkit."""


class ModelError(ZRPError, ValueError):
    """A manipulator model is invalid (the message names the joint and field)."""


class ModelFileError(ModelError):
    """A model file cannot be read (the message names the file and line)."""


class InputError(ZRPError, ValueError):
    """A function argument or option has the wrong shape, type or value."""


class OutputExistsError(ZRPError, FileExistsError):
    """Refusing to replace existing files without ``overwrite=True``.

    Args:
        paths: the files that exist (or one message, for compatibility).
        option: how the caller says "replace them"; the command line shows ``--force``.
    """

    def __init__(self, paths: object, option: str = "overwrite=True") -> None:
        if isinstance(paths, str):
            self.paths: tuple[str, ...] = ()
            super().__init__(paths)
            return
        self.paths = tuple(str(p) for p in paths)  # type: ignore[attr-defined]
        self.option = option
        super().__init__(self.message(option))

    def message(self, option: str = "overwrite=True") -> str:
        """The message, naming ``option`` as the way to replace the files."""
        if not self.paths:
            return str(self.args[0]) if self.args else "output exists"
        shown = ", ".join(self.paths[:5]) + (f" and {len(self.paths) - 5} more"
                                             if len(self.paths) > 5 else "")
        verb = "exists" if len(self.paths) == 1 else "exist"
        return f"{shown}: {verb}; pass {option} to replace"

    def __str__(self) -> str:
        return self.message(getattr(self, "option", "overwrite=True"))


class OutputIsInputError(InputError):
    """An output path is a file the same command reads (refused even with ``--force``)."""


class OutputBusyError(ZRPError, RuntimeError):
    """Another run is writing into the same output folder (it holds the folder's lock)."""

    def __init__(self, folder: object, pid: int, host: str, lock: object = None,
                 waited_s: float = 0.0) -> None:
        self.folder, self.pid, self.host = str(folder), pid, host
        self.lock = None if lock is None else str(lock)
        who = f"process {pid}" + (f" on {host}" if host else "") if pid > 0 else "another run"
        held = f" (lock file {lock}" + (f", waited {waited_s:.0f} s)" if waited_s else ")") \
            if lock is not None else ""
        super().__init__(f"{folder}: {who} is writing into this folder{held}; wait for it to "
                         "finish or choose another output folder (a lock left by a crashed run "
                         "is taken over automatically)")


class OutputKindError(InputError):
    """An output path that is not a regular file (a symbolic link, a device, a FIFO, a
    socket) or an output folder reached through a symbolic link: never replaced or written
    through, even with ``overwrite=True``."""


class UnitError(ModelError, InputError):
    """An unknown unit (the message names the field and lists the known units)."""


class IKError(ZRPError, RuntimeError):
    """Inverse kinematics failed (the message names the time and the point)."""


class UnreachableError(IKError):
    """A trajectory point lies outside the reachable workspace."""


class SingularityError(IKError):
    """The target is within reach but the arm is at a kinematic singularity there."""


class JointLimitError(IKError):
    """The motion needs a joint beyond its limits (the message names the joint and time)."""


class ZRPWarning(UserWarning):
    """Base class of this toolkit's warnings."""


class SingularityWarning(ZRPWarning):
    """The trajectory passes close to a kinematic singularity."""


class TrackingWarning(ZRPWarning):
    """Inverse kinematics could not reach the requested tolerance at some steps."""
