"""Contact mechanics: indentation laws (elastic and adhesive), their registry and the modulus fit.

A package at the level of the laws (docs/architecture.md): pure functions of SI arrays,
importing only the base modules. See docs/contact.md.

* :mod:`.models` -- Hertz paraboloid, exact sphere (Sneddon), cone, Bilodeau pyramids, thin layer
* :mod:`.adhesive` -- JKR, DMT, Maugis-Dugdale
* :mod:`.registry` -- :data:`INDENTATION_MODELS`
* :mod:`.fit` -- :func:`fit_indentation`: modulus and contact point (and w) of one curve
* :mod:`.adhesive_fit` -- the adhesive laws' fit: E, w, contact point and baseline with their covariance
"""

from .registry import INDENTATION_MODELS, IndentationModel, indentation_model

__all__ = ["INDENTATION_MODELS", "IndentationModel", "indentation_model"]
