"""What the submodules share: the type of a progress callback."""

from __future__ import annotations

from typing import Any, Callable, Optional

Progress = Optional[Callable[[str, int, int], Any]]
