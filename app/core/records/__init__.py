"""The patrol archive (SQLite, no Qt): see :mod:`app.core.records.archive` and docs/archive.md."""

from app.core.records.archive import Archive, ArchiveError, Series, bin_series
from app.core.records.paths import ENV_VAR, default_archive_path, default_data_dir

__all__ = ["Archive", "ArchiveError", "ENV_VAR", "Series", "bin_series",
           "default_archive_path", "default_data_dir"]
