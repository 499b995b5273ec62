"""occseg.Context: a thread pool kept between calls gives the same results as occseg.segment()
without one, frees its handle, and refuses bad arguments with a named error."""
import gc

import numpy as np
import pytest

import occseg


def scene():
    rng = np.random.default_rng(5)
    m = np.clip(rng.normal(0.2, 0.05, (24, 40, 36)), 0, 1).astype(np.float32)
    m[5:15, 10:20, 8:30] = 0.9
    m[18:22, :, :] = 0.5
    return m


def test_results_equal_plain_segment_for_any_pool_size():
    m = scene()
    plain = occseg.segment(m)
    for threads in (1, 2, 3):
        with occseg.Context(threads) as ctx:
            assert 1 <= ctx.threads <= threads
            for _ in range(2):  # the pool is reused
                r = occseg.segment(m, context=ctx)
                assert np.array_equal(r.labels, plain.labels)
                assert [s.voxels for s in r.segments] == [s.voxels for s in plain.segments]


def test_progress_runs_on_a_context():
    seen = []
    with occseg.Context(2) as ctx:
        occseg.segment(scene(), context=ctx, progress=lambda stage, f: seen.append(stage))
    assert seen[0] == "texture" and seen[-1] == "labelling" and len(seen) == 10


def test_handle_is_freed_by_close_and_by_collection():
    gc.collect()
    before = occseg.live_handles().get("context", 0)
    ctx = occseg.Context(2)
    assert occseg.live_handles()["context"] == before + 1
    ctx.close()
    assert ctx.closed and occseg.live_handles().get("context", 0) == before
    with pytest.raises(ValueError, match="closed"):
        occseg.segment(scene(), context=ctx)
    occseg.Context(1)  # dropped at once
    gc.collect()
    assert occseg.live_handles().get("context", 0) == before


def test_bad_arguments_are_named():
    with pytest.raises(occseg.OccsegError, match="threads = -2 is outside") as e:
        occseg.Context(-2)
    assert e.value.status == occseg.Status.EINVAL
    with pytest.raises(occseg.OccsegError, match="threads must be an int"):
        occseg.Context(1.5)
    with pytest.raises(occseg.OccsegError, match="context must be an occseg.Context"):
        occseg.segment(scene(), context="pool")


def test_recycled_result_is_closed_its_data_kept_and_later_results_right():
    m, flat = scene(), np.full((24, 40, 36), 0.1, np.float32)
    plain = occseg.segment(m)
    gc.collect()
    before = occseg.live_handles().get("result", 0)
    with occseg.Context(2) as ctx:
        r = occseg.segment(m, context=ctx)
        labels = r.labels.copy()
        ctx.recycle(r)
        assert r.closed
        assert occseg.live_handles().get("result", 0) == before  # handed over, not leaked
        assert np.array_equal(labels, plain.labels) and r.segments == plain.segments  # Python data stays
        with pytest.raises(ValueError):
            r.labels  # the array over the memory handed back (test_in_place.py: held, it is not recycled)
        with pytest.raises(ValueError):
            r.states()
        ctx.recycle(r)  # already closed: ignored
        f = occseg.segment(flat, context=ctx)  # writes into the recycled array
        assert len(f.segments) == 1 and not f.labels.any()
        ctx.recycle(f)
        again = occseg.segment(m, context=ctx)
        assert np.array_equal(again.labels, plain.labels)
        with pytest.raises(occseg.OccsegError, match="expected an occseg.Result"):
            ctx.recycle(labels)
    with pytest.raises(ValueError):
        ctx.recycle(again)  # closed context: the result is left alone
    assert not again.closed
