"""Progress bars of long writes (tqdm, on stderr)."""

from __future__ import annotations


def progress_bar(n, progress, min_n, unit, desc):
    """A tqdm bar over ``n`` items, or None: ``progress`` False never shows one, True always,
    None when ``n >= min_n`` and stderr is a terminal."""
    if progress is False or (progress is None and n < min_n):
        return None
    from tqdm import tqdm

    return tqdm(total=n, unit=unit, unit_scale=True, desc=desc, leave=False,
                disable=None if progress is None else False)
