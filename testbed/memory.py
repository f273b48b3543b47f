"""Refusing, before any work, a run whose size the memory available cannot hold.

Commands that keep something per frame or per trial until they end (``run``, ``demo``,
``study lab``, ``study tracking``, ``tune``) check its size here, in one line naming the option and the most
that fits, instead of filling the memory hours later.
"""

from __future__ import annotations


def available_memory() -> int:
    """Bytes of memory this machine can give a process now without swapping."""
    import psutil

    return psutil.virtual_memory().available


def check_fits(option: str, count: int, unit: str, each: int, held: str, *, reserved: int = 0,
               beside: str = "") -> None:
    """Raise a one-line ValueError naming ``option`` when ``count`` ``unit`` of ``each``
    bytes, held as ``held`` says, are more than the memory available now, less ``reserved``
    bytes that something else of the run holds (``beside`` names it)."""
    free = max(0, available_memory() - reserved)
    need = count * each
    if need > free:
        raise ValueError(f"{option}: {count} {unit} would hold about {gigabytes(need)} of memory {held}, more than "
                         f"the {gigabytes(free)} available{beside}; expected at most {free // each} {unit} "
                         "here")


def gigabytes(n: float) -> str:
    """
    >>> gigabytes(24.6e9), gigabytes(1.71e12), gigabytes(3e8)
    ('24.6 GB', '1,710 GB', '0.3 GB')
    """
    return f"{n / 1e9:.3g} GB" if n < 999.5e9 else f"{n / 1e9:,.0f} GB"   # 999.5 GB: "1e+03" in 3 digits
