"""Objects whose methods change them (``OnlineLoops``, ``OnlineSampler``, ``KeyedDraw``) shared
by several Python threads: the calls run one at a time, each whole, so threads hammering one
object end where a serial run ends, and no call fails because another thread is inside one
("Already borrowed")."""

from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

import inexact_loops as il

CHUNKS = 40
CHUNK = 250


def stream() -> tuple[np.ndarray, np.ndarray]:
    """A loop driven twice in 32 dimensions (so that a push takes long enough for threads to
    meet inside it): 10,000 poses with revisits."""
    rng = np.random.default_rng(7)
    n = CHUNKS * CHUNK
    angle = np.linspace(0.0, 4.0 * np.pi, n)
    points = np.c_[10 * np.cos(angle), 10 * np.sin(angle), rng.normal(0.0, 0.05, (n, 30))]
    return np.arange(n) * 0.1, points


def hammer(workers: list, seconds_cap: float = 300.0) -> list[str]:
    """Runs each worker in its own thread; returns the unexpected errors they met."""
    errors: list[str] = []

    def run(worker):
        try:
            worker()
        except Exception as error:  # noqa: BLE001 - every unexpected error is reported
            errors.append(f"{type(error).__name__}: {error}")

    threads = [threading.Thread(target=run, args=(w,)) for w in workers]
    for t in threads:
        t.start()
    for t in threads:
        t.join(seconds_cap)
        assert not t.is_alive(), "a thread hung"
    return errors


def test_threads_sharing_an_online_engine_end_as_a_serial_run():
    times, points = stream()
    serial = il.OnlineLoops(gamma=1.0, dim=32)
    for k in range(CHUNKS):
        serial.push_many(times[k * CHUNK : (k + 1) * CHUNK], points[k * CHUNK : (k + 1) * CHUNK])

    online = il.OnlineLoops(gamma=1.0, dim=32)
    sampler = il.OnlineSampler(rate=0.5, seed=3)
    done = threading.Event()
    refused = {"order": 0, "stale": 0}

    def writer():
        # Every writer offers every chunk in order; a chunk another writer pushed first is
        # refused as out of order, so the engine gets each chunk once, in order.
        for k in range(CHUNKS):
            try:
                online.push_many(
                    times[k * CHUNK : (k + 1) * CHUNK], points[k * CHUNK : (k + 1) * CHUNK]
                )
            except il.InvalidTrajectoryError as error:
                assert "not increasing" in str(error) or "after" in str(error), error
                refused["order"] += 1

    # Readers and the offerer call without a pause for as long as the writers are not done: the
    # engine's lock serves calls in the order they come, so they cannot starve a writer.
    def reader():
        while not done.is_set():
            # The table first: poses only grow, so the count read after bounds its components
            # (read before, another thread's push in between made it fail).
            table = online.components
            n = len(online)
            assert len(table["id"]) <= max(n, 1)
            if n >= 2:
                online.loop_duration(n - 1)
                repr(online)

    def offerer():
        # Updates of another thread's push are stale by the time they are offered, or not:
        # either way the sampler says so, it never fails for the engine being in use.
        update = online.push_many([], np.zeros((0, 32)))
        while not done.is_set():
            try:
                sampler.offer(online, update)
            except il.InvalidParameterError:
                refused["stale"] += 1
            update = online.push_many([], np.zeros((0, 32)))

    writers = [writer for _ in range(3)]

    def writers_then_stop():
        errors = hammer(writers)
        done.set()
        assert not errors, errors

    errors = hammer([writers_then_stop, reader, reader, offerer])
    assert not errors, errors
    assert refused["order"] == 2 * CHUNKS, refused
    assert len(online) == len(serial)
    for key, column in serial.components.items():
        np.testing.assert_array_equal(online.components[key], column, err_msg=key)
    assert online.to_loops() == serial.to_loops()


def test_threads_sharing_a_keyed_draw():
    fleet = il.urban_fleet(vehicles=2, duration_s=300.0, seed=4)
    from inexact_loops.dask import find_fleet_loops_dask

    sessions = {name: fleet.session(name) for name in fleet.names}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", il.LoopsWarning)
        tiled = find_fleet_loops_dask(sessions, 30.0, block=100).loops
    draw = tiled.draw("rho", budget=50, seed=1)
    stop = threading.Event()

    def asker():
        while not stop.is_set():
            draw.requests()
            repr(draw)

    def absorber():
        try:
            for _ in range(200):
                draw.absorb([], complete=False)
                _ = draw.done, draw.groups, draw.available
        finally:
            stop.set()

    errors = hammer([asker, asker, absorber])
    assert not errors, errors


@pytest.mark.parametrize("threads", [4])
def test_a_sampler_shared_by_threads_offers_each_update_once(threads):
    times, points = stream()
    online = il.OnlineLoops(gamma=1.0, dim=32)
    sampler = il.OnlineSampler(rate=1.0, seed=5)
    update = online.push_many(times[:2000], points[:2000])
    outcomes: list[str] = []

    def offer():
        try:
            outcomes.append(f"{len(sampler.offer(online, update))} candidates")
        except il.InvalidParameterError as error:
            assert "already offered" in str(error), error
            outcomes.append("refused")

    errors = hammer([offer] * threads)
    assert not errors, errors
    assert sorted(outcomes).count("refused") == threads - 1, outcomes
