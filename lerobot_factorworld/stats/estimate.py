"""One shape for a number with its interval, like scipy's ``ConfidenceInterval`` and result objects.

Why: an estimate travelled as 2-, 3- and 4-tuples whose order each caller had to know; a frozen value with named
fields says which end is which, at what level, and how the interval was made.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Estimate:
    """A point estimate and its two-sided interval.

    Args:
        point: The estimate (NaN where the data define none).
        low: The interval's lower end (NaN: no interval).
        high: The interval's upper end (NaN: no interval).
        level: The interval's confidence level, in (0, 1).
        method: How the interval was computed (e.g. ``"wilson"``, ``"bootstrap-t hull"``).
    """

    point: float
    low: float
    high: float
    level: float
    method: str

    def __post_init__(self) -> None:
        if not 0 < self.level < 1:
            raise ValueError(f"level must be in (0, 1), got {self.level}")
        if self.low > self.high:  # False when either is NaN: an undefined interval is allowed
            raise ValueError(f"low {self.low} above high {self.high}")

    @property
    def defined(self) -> bool:
        """Both ends of the interval are finite."""
        return math.isfinite(self.low) and math.isfinite(self.high)

    def excludes(self, value: float) -> bool:
        """The interval lies wholly above or wholly below ``value`` (False without an interval)."""
        return self.defined and (self.low > value or self.high < value)
