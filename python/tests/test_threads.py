"""The GIL is released while convshadow renders: other Python threads run meanwhile, and Ctrl-C
stops a render."""

import os
import signal
import threading
import time

import pytest

import convshadow

# About a second on one thread of the machines CI runs on (2 shared cores).
SECOND = {"width": 192, "height": 192, "slabs": 256, "threads": 1}


def test_another_thread_runs_while_a_render_runs():
    window = []
    done = threading.Event()

    def render():
        try:
            start = time.perf_counter()
            convshadow.render(**SECOND)
            window.append((start, time.perf_counter()))
        finally:
            done.set()

    worker = threading.Thread(target=render)
    worker.start()
    # This thread counts, noting (time, count) every 1000 increments.
    counter, samples = 0, []
    while not done.is_set():
        counter += 1
        if counter % 1000 == 0:
            samples.append((time.perf_counter(), counter))
    worker.join()
    assert window, "the render failed"
    start, end = window[0]
    assert end - start > 0.2, f"a render of {end - start:.3f} s is too short to tell"
    during = [(t, n) for t, n in samples if start < t < end]
    # A render that held the GIL would have stopped this thread from its start to its end
    # (no sample inside it but within a switch interval of either end); released, this thread
    # counts all along.
    assert len(during) >= 10, (len(samples), end - start)
    covered = during[-1][0] - during[0][0]
    assert covered > 0.8 * (end - start), (covered, end - start)
    assert during[-1][1] - during[0][1] >= 10_000


def test_a_render_while_another_thread_holds_the_gil_in_python_finishes():
    stop = threading.Event()
    spins = [0]

    def spin():
        while not stop.is_set():
            spins[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        image, stats = convshadow.render(width=48, height=48, slabs=64, threads=1)
    finally:
        stop.set()
        t.join()
    assert image.shape == (48, 48, 3) and stats["slabs"] == 64
    assert spins[0] > 0


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach the main thread only")
def test_ctrl_c_stops_a_render_with_keyboard_interrupt():
    # Many slabs: tens of seconds uninterrupted.
    long = {"width": 256, "height": 256, "slabs": 8192, "threads": 1}
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            convshadow.render(**long)
    finally:
        timer.cancel()
    elapsed = time.perf_counter() - start
    # Stopped within a slab or two of the signal, not after the render.
    assert elapsed < 5.0, elapsed
    # The module still renders afterwards.
    image, _ = convshadow.render(width=16, height=16, slabs=16)
    assert image.shape == (16, 16, 3)
