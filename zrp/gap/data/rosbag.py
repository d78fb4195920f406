"""ROS bags as robots record them, read without ROS (the pure-Python ``rosbags`` library):
a ROS 2 bag (its folder with ``metadata.yaml``, or one ``.mcap`` / ``.db3`` file of it, read
alone when no ``metadata.yaml`` lies beside it) or a ROS 1 ``.bag``.

:func:`read_topic` picks one topic of a message type (``topic`` named, else the only one of
that type; several, or none, is an :class:`~zrp.errors.InputError` naming the bag's topics
and types) and yields ``(log time ns, message)``; :func:`stamp_ns` is a message header's
stamp. ``rosbags`` is imported only when a bag is read (``zrp --help`` stays fast). Cost:
the bag's messages of that topic, deserialised one by one (about 20 us a JointState).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from zrp.errors import InputError

__all__ = ["BAG_SUFFIXES", "JOINT_STATE", "POINT", "POSE", "is_bag", "read_topic", "stamp_ns"]

#: File suffixes read as bags (a folder holding ``metadata.yaml`` is one too).
BAG_SUFFIXES = (".bag", ".mcap", ".db3")
JOINT_STATE = "sensor_msgs/msg/JointState"
POINT = "geometry_msgs/msg/PointStamped"
POSE = "geometry_msgs/msg/PoseStamped"


def is_bag(path: str | os.PathLike[str]) -> bool:
    """A ROS bag by its suffix, or a folder holding ``metadata.yaml`` (ROS 2)."""
    p = Path(path)
    return p.suffix.lower() in BAG_SUFFIXES or (p.is_dir() and (p / "metadata.yaml").is_file())


class _Lone:
    """One ROS 2 storage file without its ``metadata.yaml``: the storage plugin alone, the
    messages deserialised with the ROS 2 Humble type store (JointState, PointStamped and
    PoseStamped are the same in every distribution)."""

    def __init__(self, path: Path) -> None:
        from rosbags.rosbag2.storage_mcap import McapReader
        from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader
        from rosbags.typesys import Stores, get_typestore

        plugin = McapReader if path.suffix.lower() == ".mcap" else Sqlite3Reader
        self.storage = plugin(path)
        self.store = get_typestore(Stores.ROS2_HUMBLE)

    def __enter__(self) -> _Lone:
        self.storage.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.storage.close()

    @property
    def connections(self) -> list[Any]:
        return list(self.storage.connections)

    def messages(self, connections: list[Any]) -> Iterator[tuple[Any, int, bytes]]:
        return self.storage.messages(connections)

    def deserialize(self, raw: bytes, msgtype: str) -> Any:
        return self.store.deserialize_cdr(raw, msgtype)


def _errors() -> tuple[type[BaseException], ...]:
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Error1
    from rosbags.rosbag2 import ReaderError as Error2
    from rosbags.serde import SerdeError

    return AnyReaderError, Error1, Error2, SerdeError, OSError, KeyError, ValueError


@contextmanager
def _open(path: Path) -> Iterator[Any]:
    from rosbags.highlevel import AnyReader

    if path.is_dir() or path.suffix.lower() == ".bag":
        with AnyReader([path]) as reader:
            yield reader
    elif (path.parent / "metadata.yaml").is_file():
        with AnyReader([path.parent]) as reader:
            yield reader
    else:
        with _Lone(path) as reader:
            yield reader


def _choose(connections: list[Any], msgtypes: tuple[str, ...], topic: str | None,
            option: str, src: str) -> list[Any]:
    held = sorted({(c.topic, c.msgtype) for c in connections})
    listed = ", ".join(f"{t} ({m})" for t, m in held) or "none"
    if topic is not None:
        chosen = [c for c in connections if c.topic == topic]
        if not chosen:
            raise InputError(f"{option} {topic}: {src} has no such topic; its topics: {listed}")
        if any(c.msgtype not in msgtypes for c in chosen):
            raise InputError(f"{option} {topic}: in {src} it is {chosen[0].msgtype}, not "
                             f"{' or '.join(msgtypes)}")
        return chosen
    chosen = [c for c in connections if c.msgtype in msgtypes]
    names = sorted({c.topic for c in chosen})
    if not names:
        raise InputError(f"{src}: no {' or '.join(msgtypes)} topic; its topics: {listed}")
    if len(names) > 1:
        raise InputError(f"{src}: {len(names)} {' or '.join(msgtypes)} topics "
                         f"({', '.join(names)}); choose one with {option}")
    return chosen


def read_topic(path: str | os.PathLike[str], msgtypes: tuple[str, ...], *,
               topic: str | None = None, option: str = "--topic",
               max_messages: int | None = None) -> Iterator[tuple[int, Any]]:
    """``(log time ns, message)`` of one topic of ``msgtypes`` in the bag at ``path``, in log
    time order (module docstring); ``option`` names the choosing option in messages; more
    than ``max_messages`` messages is refused."""
    p = Path(path)
    src = p.name
    if not p.exists():
        raise InputError(f"{path}: no such file or folder")
    errors = _errors()
    try:
        with _open(p) as reader:
            chosen = _choose(list(reader.connections), msgtypes, topic, option, src)
            for k, (conn, t_ns, raw) in enumerate(reader.messages(connections=chosen)):
                if max_messages is not None and k >= max_messages:
                    raise InputError(f"{src}: more than {max_messages} messages on "
                                     f"{chosen[0].topic}; pass a larger limit to read it")
                yield int(t_ns), reader.deserialize(raw, conn.msgtype)
    except InputError:
        raise
    except errors as exc:
        raise InputError(f"{src}: cannot read the bag ({type(exc).__name__}: {exc})") from None


def stamp_ns(msg: Any) -> int:
    """The message header's stamp, ns (0 when the header has none)."""
    stamp = msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
