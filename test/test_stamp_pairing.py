# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Pairing colour and depth by nearest stamp (ApproximateTime-like), without ROS."""

from dgmod_ros.stamp_pairing import StampPairer
import pytest

MS = 1_000_000


def _feed(pairer, events):
    pairs = []
    for stream, stamp in events:
        add = pairer.add_primary if stream == 'c' else pairer.add_secondary
        pairs += add(stamp * MS, f'{stream}{stamp}')
    return pairs


def test_equal_stamps_pair_at_once_in_either_order():
    pairer = StampPairer(slop_ns=5 * MS)
    assert _feed(pairer, [('c', 0)]) == []
    assert _feed(pairer, [('d', 0)]) == [('c0', 'd0')]
    assert _feed(pairer, [('d', 33), ('c', 33)]) == [('c33', 'd33')]
    assert pairer.pairs_ == 2 and pairer.unpaired_primary_ == pairer.unpaired_secondary_ == 0


def test_each_item_pairs_with_its_nearest_partner():
    pairer = StampPairer(slop_ns=20 * MS)
    # Depth 4 ms after colour at 30 frames/s: each depth waits for the next
    # colour frame, which proves to be farther.
    events = [('c', 0), ('d', 4), ('c', 33), ('d', 37), ('c', 66), ('d', 70), ('c', 100)]
    assert _feed(pairer, events) == [('c0', 'd4'), ('c33', 'd37'), ('c66', 'd70')]
    # Depth at 15 frames/s against colour at 30: every other colour frame unpaired.
    pairer = StampPairer(slop_ns=20 * MS)
    events = [('c', 0), ('d', 1), ('c', 33), ('c', 66), ('d', 67), ('c', 100), ('c', 133),
              ('d', 134), ('c', 166)]
    assert _feed(pairer, events) == [('c0', 'd1'), ('c66', 'd67'), ('c133', 'd134')]
    assert pairer.unpaired_primary_ == 2 and pairer.unpaired_secondary_ == 0


def test_a_nearer_later_partner_wins():
    pairer = StampPairer(slop_ns=20 * MS)
    # d10 is within the slop of c0 but nearer c12, which comes later; the
    # pair is certain once a depth image farther from c12 arrives.
    assert _feed(pairer, [('c', 0), ('d', 10), ('c', 12)]) == []
    assert pairer.unpaired_primary_ == 1
    assert _feed(pairer, [('d', 43)]) == [('c12', 'd10')]
    # Symmetric: c20 within the slop of d10, but d19 is nearer.
    pairer = StampPairer(slop_ns=20 * MS)
    assert _feed(pairer, [('d', 10), ('c', 20), ('d', 19), ('d', 52)]) == [('c20', 'd19')]
    assert pairer.unpaired_secondary_ == 1


def test_items_beyond_the_slop_are_dropped_and_counted():
    pairer = StampPairer(slop_ns=5 * MS)
    assert _feed(pairer, [('d', 0), ('c', 50), ('c', 100), ('d', 101)]) == []
    assert pairer.unpaired_secondary_ == 1 and pairer.unpaired_primary_ == 1
    assert _feed(pairer, [('c', 133)]) == [('c100', 'd101')]


def test_a_stalled_stream_bounds_the_queue_and_time_going_back_starts_over():
    pairer = StampPairer(slop_ns=5 * MS, queue_size=3)
    assert _feed(pairer, [('c', t) for t in range(0, 330, 33)]) == []
    assert len(pairer.primary_) == 3 and pairer.unpaired_primary_ == 7
    assert _feed(pairer, [('d', 10)]) == []       # older than every waiting colour frame
    assert pairer.unpaired_secondary_ == 1
    assert _feed(pairer, [('c', 0), ('d', 0)]) == [('c0', 'd0')]   # bag restarted
    assert pairer.unpaired_primary_ == 10
    # Time going back drops what waits from the old timeline on both streams.
    assert _feed(pairer, [('c', 50), ('d', 52), ('c', 3)]) == []
    assert [s for s, _ in pairer.primary_] == [3 * MS] and not pairer.secondary_
    assert pairer.unpaired_primary_ == 11 and pairer.unpaired_secondary_ == 2


def test_parameters_are_validated():
    with pytest.raises(ValueError, match='slop_ns'):
        StampPairer(slop_ns=-1).validate()
    with pytest.raises(ValueError, match='queue_size'):
        StampPairer(slop_ns=0, queue_size=0).validate()


def test_every_dropped_item_is_handed_to_on_drop():
    dropped = []
    pairer = StampPairer(slop_ns=5 * MS, queue_size=2,
                         on_drop=lambda primary, payload: dropped.append((primary, payload)))
    # Unpaired by stamp, by a full queue, by time going back, and by clear().
    _feed(pairer, [('c', 0), ('d', 20), ('c', 40), ('c', 73), ('c', 106)])
    _feed(pairer, [('d', 10)])
    _feed(pairer, [('c', 200)])
    pairer.clear()
    # Time going back drops the newer colour frames newest first.
    assert dropped == [(True, 'c0'), (False, 'd20'), (True, 'c40'), (True, 'c106'),
                       (True, 'c73'), (False, 'd10'), (True, 'c200')]
    assert pairer.unpaired_primary_ == 5 and pairer.unpaired_secondary_ == 2
