"""A finished sweep as a table: one row per variant (the ``sweep.csv`` columns)."""

from __future__ import annotations

from dataclasses import dataclass

from cdpr_design.io.tables import Table


@dataclass
class SweepTable(Table):
    """Every variant of a sweep, in variant order.

    ``header``: ``variant``, the varied keys, the ``design_report.csv`` figures,
    ``error`` (empty unless the variant failed); ``rows``: one list per variant.
    """

    header: list
    rows: list

    def columns(self) -> dict:
        """Column name -> list of the variants' values."""
        return {h: [r[i] for r in self.rows] for i, h in enumerate(self.header)}

    def failed(self) -> list:
        """The rows of variants that could not be evaluated (their ``error`` says why)."""
        i = self.header.index("error")
        return [r for r in self.rows if r[i]]
