"""irid works in a fork()ed child after its parent used it: the worker
threads of the parent's pool do not exist in the child (fork copies only the
calling thread), so a child that queued work on them waited forever. This is
multiprocessing's default start method on Linux before Python 3.14.

Each test bounds the child's run with a timeout, so a regression fails
instead of hanging the suite."""

import multiprocessing
import os
import signal
import time

import numpy as np
import pytest

import irid

pytestmark = [
    pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork()"),
    # Python 3.12+ warns that forking a process with threads (irid's pool)
    # may deadlock; irid's own state is made safe for it, which these test.
    pytest.mark.filterwarnings("ignore::DeprecationWarning"),
]

TIMEOUT_S = 60


def film():
    return irid.Stack(ambient=1.0, layers=[(1.33, 300.0), ("TiO2", 60.0)], substrate=1.5)


def every_path(tmp_dir):
    """One call of each entry point that runs on the thread pool, large
    enough to be split across threads, and small calls, which run on the
    calling thread; returns the arrays they produce."""
    w = np.linspace(380.0, 780.0, 401)
    n = np.stack([np.ones_like(w), np.full_like(w, 1.33), np.full_like(w, 1.5)], axis=1)
    grid = irid.coherent(n, [np.inf, 300.0, np.inf], np.linspace(0.0, 89.0, 90), w)
    solved = film().solve(np.linspace(400.0, 700.0, 31), [0.0, 30.0, 60.0], thickness_nm=np.linspace(0, 500, 11))
    lut = irid.bake(film(), thickness_nm=(0, 500), resolution=(32, 8), validation_points=500)
    path = os.path.join(tmp_dir, f"t-{os.getpid()}.exr")
    lut.save(path)
    loaded = irid.Lut.load(path)
    r, t = loaded.sample(np.linspace(0, 500, 20_000), np.linspace(0.1, 1.0, 20_000))
    stats = lut.validate(points=2000, seed=3)
    colour = film().color([0.0, 45.0])
    rng = np.random.default_rng(4)
    r_points, t_points = film().response(rng.uniform(0, 1, 6000), rng.uniform(380, 780, 6000), rng.uniform(0, 500, 6000))
    small = [
        irid.coherent([1.0, 1.33, 1.5], [np.inf, 300.0, np.inf], [10.0], [550.0])["R_avg"],
        film().solve([550.0], [10.0])["R"],
        np.concatenate(loaded.sample(250.0, 0.5)),
        np.array(film().response(0.5, 550.0, 120.0)),
    ]
    return {
        "small": np.concatenate([np.ravel(a) for a in small]),
        "coherent": grid["R_avg"],
        "solve": solved["R"],
        "bake": lut.data,
        "sample": np.concatenate([r, t]),
        "validate": np.array(stats["max_abs"] + stats["mean_abs"]),
        "color": colour["reflectance_rgb"],
        "response": np.concatenate([r_points, t_points]),
    }


def same_results(a, b):
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def in_forked_child(check):
    """Runs check() in an os.fork()ed child: True when it returns True, False
    when it returns False, raises or outlives the timeout (then it is killed)."""
    pid = os.fork()
    if pid == 0:
        status = 3
        try:
            status = 0 if check() else 1
        finally:
            os._exit(status)
    deadline = time.monotonic() + TIMEOUT_S
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return False
        time.sleep(0.02)


def test_os_fork_child_computes_after_the_parent(tmp_path):
    parent = every_path(tmp_path)
    assert in_forked_child(lambda: same_results(every_path(tmp_path), parent))


def test_multiprocessing_fork_workers_compute_after_the_parent(tmp_path):
    parent = every_path(tmp_path)
    context = multiprocessing.get_context("fork")
    with context.Pool(2) as pool:
        jobs = [pool.apply_async(every_path, (str(tmp_path),)) for _ in range(2)]
        children = [job.get(timeout=TIMEOUT_S) for job in jobs]
    for child in children:
        assert same_results(child, parent)


def test_a_child_of_a_child_computes_too(tmp_path):
    # The pool the first child builds must itself be replaced in its own child.
    parent = every_path(tmp_path)
    context = multiprocessing.get_context("fork")
    with context.Pool(1) as pool:
        ok = pool.apply_async(child_and_grandchild_agree, (str(tmp_path), parent)).get(timeout=2 * TIMEOUT_S)
    assert ok


def child_and_grandchild_agree(tmp_dir, parent):
    agree = lambda: same_results(every_path(tmp_dir), parent)  # noqa: E731
    return agree() and in_forked_child(agree)
