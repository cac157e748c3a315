"""Stopping a search once its answer has stopped improving: :class:`StallRule`, followed
during one search by a :class:`StallWatch`.

After its first path a sampling planner keeps shortening it, by less and less. The rule
looks at the best length every :attr:`StallRule.check_every` samples after the first
path (a fifth of the stretch, rounded up) and compares it with the best length
:data:`CHECKS` checks earlier (at least :attr:`StallRule.samples` samples before, the
first path's own length at the first comparison): when it has shortened by no more than
:attr:`StallRule.fraction` of that length, the search stops. The rule counts samples,
never wall time, so the same seed stops at the same sample on any machine; it watches the
search's own best length, which shortens steadily, not the post-processed one, which
shortens in steps.

The default, 0.5 % over 5,000 samples, was chosen on the course maps and the built-in
worlds (``bench/planning_budget.py``, docs/planning.md): against the fixed 50,000 samples
after the first path, the refined length was 0.12 % longer on the median map and 0.43 %
on the worst (means over seeds 0-9; 1.5 % at most for any one seed) for 15-42 % of the
CPU.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from quadnav.limits import STALL_FRACTION, STALL_SAMPLES

#: Checks per stretch: the best length is compared with the one this many checks back.
CHECKS = 5
#: The default rule: at most this fraction of the length gained over ...
DEFAULT_STALL_FRACTION = 0.005
#: ... this many samples ends the search.
DEFAULT_STALL_SAMPLES = 5_000


@dataclass(frozen=True)
class StallRule:
    """Stop a search whose best length, in :data:`CHECKS` checks (at least ``samples``
    samples), shortened by at most ``fraction`` of itself (see the module docstring).

    Attributes:
        fraction: the least relative shortening, in
            :data:`~quadnav.limits.STALL_FRACTION` (0: stop only when the best length did
            not shorten at all).
        samples: the stretch of samples it is measured over, in
            :data:`~quadnav.limits.STALL_SAMPLES`.
    """

    fraction: float = DEFAULT_STALL_FRACTION
    samples: int = DEFAULT_STALL_SAMPLES

    def __post_init__(self) -> None:
        STALL_FRACTION.check(self.fraction, "stall fraction")
        STALL_SAMPLES.check(self.samples, "stall samples")

    @property
    def check_every(self) -> int:
        """Samples between two checks: a :data:`CHECKS`-th of the stretch, rounded up."""
        return -(-self.samples // CHECKS)

    def describe(self) -> str:
        """The rule in words, e.g. ``the best length shortened by at most 0.5 % over
        5,000 samples``."""
        return (f"the best length shortened by at most {100 * self.fraction:g} % over "
                f"{CHECKS * self.check_every:,} samples")


def stall_rule(samples: int, fraction: float) -> StallRule | None:
    """The rule over a stretch of ``samples`` (0: none, a fixed budget) and ``fraction``."""
    return StallRule(fraction, samples) if samples else None


class StallWatch:
    """One search's checks of a :class:`StallRule`, from its first path on.

    Attributes:
        next_check: the sample count (the search's iterations) of the next check.
    """

    def __init__(self, rule: StallRule, first: int, length: float) -> None:
        """Follow a search whose first path, ``length`` m, came at sample ``first``."""
        self._rule = rule
        self._lengths = deque([length], maxlen=CHECKS + 1)
        self.next_check = first + rule.check_every

    def stalled(self, length: float) -> bool:
        """Record the best ``length``, m, at the check at :attr:`next_check` samples and
        say whether the rule ends the search there; the next check follows."""
        self._lengths.append(length)
        self.next_check += self._rule.check_every
        if len(self._lengths) <= CHECKS:
            return False
        before = self._lengths[0]
        return before - length <= self._rule.fraction * before
