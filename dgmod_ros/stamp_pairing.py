# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Pair two message streams by nearest stamp, as message_filters' ApproximateTime does.

message_filters is not available here (and its Python ApproximateTimeSynchronizer
has no notion of a primary stream), so this is written in the package and has
no ROS import: items are ``(stamp_ns, payload)``.
"""

from collections import deque


class StampPairer:
    """
    One-to-one pairing of a primary and a secondary stream by nearest stamp.

    The node feeds colour frames (with their masks) as the primary stream and
    depth images as the secondary one. A pair is emitted once each item is
    the other's nearest partner within ``slop_ns`` and no later message can
    change that (stamps of each stream are taken to rise; the next message of
    the other stream decides). An item that can no longer be paired is
    dropped and counted: a primary without partner already had its mask, so
    only its depth outputs are missing; an unpaired secondary is of no use.

    Parameters
    ----------
    slop_ns : int
        Largest stamp difference of a pair, in nanoseconds.
    queue_size : int
        Items kept per stream while waiting for a partner; the oldest goes
        first (counted as unpaired) when a stream stalls.
    on_drop : callable or None
        Called as ``on_drop(primary, payload)`` for every item dropped without
        partner (``primary`` True for the primary stream): the node publishes
        a held colour mask then.

    Attributes
    ----------
    pairs_ : int
        Pairs emitted.
    unpaired_primary_, unpaired_secondary_ : int
        Items dropped without partner.

    """

    def __init__(self, slop_ns, queue_size=10, on_drop=None):
        self.slop_ns = slop_ns
        self.queue_size = queue_size
        self.on_drop = on_drop
        self.reset()

    def validate(self):
        """Check the parameters; return self."""
        if not self.slop_ns >= 0:
            raise ValueError(f'slop_ns must be >= 0, got {self.slop_ns!r}')
        if int(self.queue_size) < 1:
            raise ValueError(f'queue_size must be >= 1, got {self.queue_size!r}')
        return self

    def reset(self):
        """Forget the waiting items and zero the counters."""
        self.primary_ = deque()
        self.secondary_ = deque()
        self._newest = {}                       # stream -> newest stamp seen
        self.pairs_ = 0
        self.unpaired_primary_ = 0
        self.unpaired_secondary_ = 0

    def clear(self):
        """Drop the waiting items, counted as unpaired (the inputs started over)."""
        while self.primary_:
            self._drop(self.primary_)
        while self.secondary_:
            self._drop(self.secondary_)

    def add_primary(self, stamp_ns, payload):
        """Add a primary item; return the pairs ``(primary, secondary)`` now complete."""
        return self._add(self.primary_, stamp_ns, payload)

    def add_secondary(self, stamp_ns, payload):
        """Add a secondary item; return the pairs ``(primary, secondary)`` now complete."""
        return self._add(self.secondary_, stamp_ns, payload)

    def _add(self, queue, stamp_ns, payload):
        stream = 'primary' if queue is self.primary_ else 'secondary'
        newest = self._newest.get(stream)
        self._newest[stream] = stamp_ns
        if newest is not None and stamp_ns < newest:
            # Time went back (a bag restarted, a driver reset): what waits
            # belongs to the old timeline, except the other stream's items
            # that already came from the new one.
            while queue:
                self._drop(queue)
            other = self.secondary_ if queue is self.primary_ else self.primary_
            while other and other[-1][0] > stamp_ns + self.slop_ns:
                self._discard(other, other.pop())
        queue.append((stamp_ns, payload))
        while len(queue) > self.queue_size:
            self._drop(queue)
        return self._match()

    def _drop(self, queue):
        self._discard(queue, queue.popleft())

    def _discard(self, queue, item):
        primary = queue is self.primary_
        if primary:
            self.unpaired_primary_ += 1
        else:
            self.unpaired_secondary_ += 1
        if self.on_drop is not None:
            self.on_drop(primary, item[1])

    def _match(self):
        pairs = []
        primary, secondary = self.primary_, self.secondary_
        while primary and secondary:
            p, s = primary[0][0], secondary[0][0]
            if s < p - self.slop_ns:           # too old for p and every later primary
                self._drop(secondary)
            elif p < s - self.slop_ns:
                self._drop(primary)
            elif len(secondary) > 1 and abs(secondary[1][0] - p) < abs(s - p):
                self._drop(secondary)          # p prefers the next one; s has no better
            elif len(primary) > 1 and abs(primary[1][0] - s) < abs(p - s):
                self._drop(primary)
            elif (s < p and len(secondary) == 1) or (p < s and len(primary) == 1):
                break                          # the next message may be nearer: wait
            else:
                pairs.append((primary.popleft()[1], secondary.popleft()[1]))
                self.pairs_ += 1
        return pairs
