"""No handle is freed under a running call: a Map or Context closed by another thread while it is
segmented, or from the progress callback of that very segmentation, stays alive until the C call
returns, which then finishes normally; a map a call uses refuses to be changed.

The scenarios that crashed, deadlocked or failed with a bogus error before the fix run in a child
interpreter (this file run as a script), so that a crash or a hang fails one test with its output
instead of killing the suite."""
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import occseg


def scene():
    rng = np.random.default_rng(24)
    m = np.clip(rng.normal(0.2, 0.05, (40, 48, 44)), 0, 1).astype(np.float32)
    m[5:15, 10:20, 8:30] = 0.9
    m[20:24, :, :] = 0.5
    return m


def live(kind):
    return occseg.live_handles().get(kind, 0)


# ---- scenarios run in a child interpreter ----------------------------------------------------

def map_closed_in_its_progress_callback():
    m = scene()
    ref = occseg.segment(m, threads=1)
    before = live("map")
    mp = occseg.Map.from_array(m)
    during = []

    def progress(stage, fraction):
        if not mp.closed:  # at the start of the texture stage, before the map is read
            mp.close()
            during.append(live("map"))
            with pytest.raises(ValueError, match="closed"):
                mp.dims  # closed at once for new calls

    r = occseg.segment(mp, threads=1, progress=progress)
    assert during == [before + 1], "the map was freed under the running segmentation"
    assert live("map") == before, "the map was not freed when the segmentation returned"
    assert np.array_equal(r.labels, ref.labels) and r.segments == ref.segments
    with pytest.raises(ValueError, match="closed"):
        occseg.segment(mp)


def context_closed_in_its_progress_callback():
    m = scene()
    ref = occseg.segment(m, threads=2)
    before = live("context")
    ctx = occseg.Context(2)
    during = []

    def progress(stage, fraction):
        if not ctx.closed:
            ctx.close()
            during.append(live("context"))

    r = occseg.segment(m, threads=2, context=ctx, progress=progress)
    assert during == [before + 1], "the context was freed under the running segmentation"
    assert live("context") == before
    assert np.array_equal(r.labels, ref.labels) and r.segments == ref.segments
    with pytest.raises(ValueError, match="closed"):
        occseg.segment(m, context=ctx)


def _closed_by_another_thread(kind):
    """Another thread closes the map (or context) while the segmentation that uses it waits in
    its first progress callback; the callback returns only after that close() has returned."""
    m = scene()
    ref = occseg.segment(m, threads=2)
    before = live(kind)
    mp = occseg.Map.from_array(m)
    ctx = occseg.Context(2)
    victim = mp if kind == "map" else ctx
    in_callback, closed, during, errors = threading.Event(), threading.Event(), [], []

    def progress(stage, fraction):
        if not in_callback.is_set():
            in_callback.set()
            closed.wait()

    def closer():
        try:
            in_callback.wait()
            victim.close()
            during.append(live(kind))
        except BaseException as e:  # reported by the main thread
            errors.append(e)
        finally:
            closed.set()

    t = threading.Thread(target=closer)
    t.start()
    try:
        r = occseg.segment(mp, threads=2, context=ctx, progress=progress)
    finally:
        in_callback.set()
        t.join()
    assert not errors, errors
    assert victim.closed and during == [before + 1], f"the {kind} was freed under the running segmentation"
    assert np.array_equal(r.labels, ref.labels) and r.segments == ref.segments
    mp.close()
    ctx.close()
    assert live(kind) == before


def map_closed_by_another_thread():
    _closed_by_another_thread("map")


def context_closed_by_another_thread():
    _closed_by_another_thread("context")


SCENARIOS = {f.__name__: f for f in (map_closed_in_its_progress_callback, context_closed_in_its_progress_callback,
                                     map_closed_by_another_thread, context_closed_by_another_thread)}


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_closed_while_a_segmentation_runs_on_it(name):
    # The timeout only turns a hang (the deadlock of a context freed under its own call) into a
    # failure; a passing run takes a small fraction of it.
    r = subprocess.run([sys.executable, os.path.abspath(__file__), name], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, f"exit code {r.returncode}\n{r.stdout}\n{r.stderr}"
    assert r.stdout.strip() == "ok " + name, r.stdout + r.stderr


# ---- in-process tests --------------------------------------------------------------------------

def handle_of(kind):
    """A new object of each kind that owns a C handle."""
    if kind == "map":
        return occseg.Map.from_array(scene())
    if kind == "result":
        r = occseg.segment(scene(), threads=1)
        r._let_go()  # its labels array is a use of its own (test_in_place.py); here only the calls'
        return r
    if kind == "context":
        return occseg.Context(1)
    from occseg._segment import _Params
    return _Params()


@pytest.mark.parametrize("kind", ["map", "result", "context", "params"])
def test_every_handle_closed_while_in_use_is_freed_by_its_last_use(kind):
    obj = handle_of(kind)
    before = live(kind)
    with obj._used() as h1:
        with obj._used() as h2:  # two calls at once (two threads, or a call and its callback)
            obj.close()
            assert obj.closed and h1 == h2
            with pytest.raises(ValueError, match="closed"):
                with obj._used():
                    pass
            obj.close()  # again: nothing
        assert live(kind) == before  # one call still runs
    assert live(kind) == before - 1
    obj.close()
    assert live(kind) == before - 1


def test_a_map_in_use_refuses_changes_and_keeps_its_values():
    m = scene()
    mp = occseg.Map.from_array(m, voxel_size=0.5, origin=(1, 2, 3))
    errors = []

    def progress(stage, fraction):
        if stage == "texture" and fraction == 0.0:
            for name, value in (("voxel_size", 2.0), ("origin", (0, 0, 0))):
                try:
                    setattr(mp, name, value)
                except occseg.OccsegValueError as e:
                    errors.append(e)

    r = occseg.segment(mp, threads=1, progress=progress)
    assert [e.status for e in errors] == [occseg.Status.EINVAL] * 2, errors
    assert "occseg.Map.voxel_size: the map is in use by 1 running call" in errors[0].message
    assert "occseg.Map.origin: the map is in use" in errors[1].message
    assert isinstance(errors[0], ValueError)
    assert (mp.voxel_size, mp.origin) == (0.5, (1.0, 2.0, 3.0))
    assert (r.voxel_size, r.origin) == (0.5, (1.0, 2.0, 3.0))
    mp.voxel_size = 2.0  # once the call has returned, it may change
    assert mp.voxel_size == 2.0


def test_a_map_segmented_from_another_thread_refuses_changes():
    mp = occseg.Map.from_array(scene(), voxel_size=0.5)
    in_callback, done, errors = threading.Event(), threading.Event(), []

    def progress(stage, fraction):
        if not in_callback.is_set():
            in_callback.set()
            done.wait()

    def setter():
        try:
            in_callback.wait()
            mp.voxel_size = 2.0
        except BaseException as e:
            errors.append(e)
        finally:
            done.set()

    t = threading.Thread(target=setter)
    t.start()
    try:
        occseg.segment(mp, threads=1, progress=progress)
    finally:
        in_callback.set()
        t.join()
    assert len(errors) == 1 and isinstance(errors[0], occseg.OccsegValueError), errors
    assert mp.voxel_size == 0.5


def test_recycling_a_result_in_use_closes_it_and_frees_it_after_the_use():
    m = scene()
    with occseg.Context(1) as ctx:
        r = occseg.segment(m, context=ctx)
        expected = r.labels.copy()
        before = live("result")
        with r._used():  # e.g. another thread inside r.write()
            ctx.recycle(r)
            assert r.closed and live("result") == before  # not handed to the context under the call
        assert live("result") == before - 1
        again = occseg.segment(m, context=ctx)
        assert np.array_equal(again.labels, expected)


if __name__ == "__main__":
    SCENARIOS[sys.argv[1]]()
    print("ok", sys.argv[1])
