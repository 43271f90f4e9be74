"""Camera catalogue (cdf/tables/*.yaml) and camera definition files: generate, validate, host.

No network I/O here except where a caller asks `validate` to fetch a URL.
"""

from cdf.errors import CdfError, WirisError

__all__ = ["CdfError", "WirisError"]
