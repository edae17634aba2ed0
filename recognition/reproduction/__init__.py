"""Reproduction of the thesis's tables and figures, thesis and measured values side by side."""

from recognition.reproduction.tables import TableResult, markdown_table

__all__ = ["TableResult", "markdown_table"]
