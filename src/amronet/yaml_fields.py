"""Pydantic field types for values read by :func:`amronet.yaml_loading.load_yaml`.

Kept apart from the reader so that reading a file or a ``--set`` value does not wait for pydantic.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BeforeValidator, StrictBool

from amronet.yaml_loading import as_bool

__all__ = ["YamlBool"]

YamlBool = Annotated[StrictBool, BeforeValidator(as_bool)]
"""A boolean field: ``true`` / ``false``, or the words ``yes`` / ``no``, ``on`` / ``off``, ``y`` / ``n`` in any
case (:data:`amronet.yaml_loading.BOOL_WORDS`; YAML 1.2 reads them as strings). Numbers (``1``, ``0``) and other
strings are refused, where pydantic's lax ``bool`` would take ``1``, ``'t'`` or ``'0'``."""
