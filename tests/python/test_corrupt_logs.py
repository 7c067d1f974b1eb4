"""Corrupt logs from Python: a corrupt log raises an exception whose message is
one line naming the file and the offset (no library backtrace, no escape sequences), a string
declaring 4 GiB allocates nothing, and a file without line breaks fails at its first line."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

import inexact_loops as il

MAGIC = b"\x89MCAP0\r\n"


def record(opcode: int, body: bytes) -> bytes:
    return struct.pack("<BQ", opcode, len(body)) + body


def string(data: bytes) -> bytes:
    return struct.pack("<I", len(data)) + data


def mcap(*records: bytes) -> bytes:
    """A small MCAP file: magic, header, ``records``, data end, footer, magic."""
    header = record(0x01, string(b"") + string(b"test"))
    end = record(0x0F, bytes(4)) + record(0x02, bytes(20))
    return MAGIC + header + b"".join(records) + end + MAGIC


def one_line(error: BaseException, path: Path) -> str:
    message = str(error)
    assert "\n" not in message and "\x1b" not in message, repr(message)
    assert "backtrace" not in message.lower() and "registry" not in message, message
    assert message.startswith(str(path)), message
    return message


def test_a_non_utf8_topic_is_one_line(tmp_path: Path) -> None:
    channel = struct.pack("<HH", 1, 0) + string(b"/p\xffose") + string(b"json") + string(b"")
    path = tmp_path / "non-utf8.mcap"
    path.write_bytes(mcap(record(0x04, channel)))
    for read in (il.read_trajectory, il.list_topics):
        with pytest.raises(il.LoopsIOError) as caught:
            read(path)
        message = one_line(caught.value, path)
        assert "offset 29: " in message and "its topic is not UTF-8" in message, message


def test_a_name_declaring_4_gib_is_an_error_not_an_allocation(tmp_path: Path) -> None:
    schema = struct.pack("<HI", 1, 0xFFFFFFFF) + b"geometry_msgs"
    path = tmp_path / "huge-name.mcap"
    path.write_bytes(mcap(record(0x03, schema)))
    with pytest.raises(il.LoopsIOError) as caught:
        il.read_trajectory(path)
    assert "its name is declared 4294967295 bytes long" in one_line(caught.value, path)


def test_a_file_without_line_breaks_fails_at_line_1(tmp_path: Path) -> None:
    path = tmp_path / "long.tum"
    path.write_bytes(b"0" * (3 << 20))
    with pytest.raises(il.LoopsIOError) as caught:
        il.read_trajectory(path)
    assert "line 1: the line is longer than 1 MiB" in one_line(caught.value, path)
