"""Outputs aimed at a stream (``/dev/null`` through a link, a FIFO) are written into, never
replaced: every writer of the package goes through loops-io's one atomic writer, whose rename
would otherwise put a file where the device or the link was."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il
from inexact_loops import _core, viewers
from inexact_loops.dask._parquet import write_pose_parquet


@pytest.fixture
def null(tmp_path: Path) -> Path:
    link = tmp_path / "null"
    link.symlink_to("/dev/null")
    return link


def still_the_device(link: Path) -> bool:
    return link.is_symlink() and link.is_char_device()


def test_every_writer_writes_into_a_link_to_dev_null(null: Path, tmp_path: Path) -> None:
    for overwrite in (False, True):
        _core.write_file(null, b"into the device", overwrite=overwrite)
        assert still_the_device(null)
    s = np.linspace(0, 4 * np.pi, 200)
    traj = il.Trajectory(s, 10 * np.c_[np.cos(s), np.sin(s)])
    write_pose_parquet(null, traj)
    assert still_the_device(null)
    loops = il.find_loops(traj, gamma=1.0, separation=None)
    samples = il.sample(loops, "rho", budget=5, seed=0, trajectory=traj)
    viewers.to_mcap(loops, samples, null, trajectory=traj, overwrite=True)
    assert still_the_device(null)
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_fifo_receives_the_whole_file(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    _core.write_file(fifo, b"a" * 200_000)
    reader.join(timeout=30)
    assert received == [b"a" * 200_000]
    assert fifo.is_fifo()


def test_a_socket_is_refused_and_left(tmp_path: Path) -> None:
    import socket

    path = tmp_path / "socket"
    with socket.socket(socket.AF_UNIX) as listener:
        listener.bind(str(path))
        with pytest.raises(OSError, match="it is a socket, not a file"):
            _core.write_file(path, b"no", overwrite=True)
        assert path.is_socket()
