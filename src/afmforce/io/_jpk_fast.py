"""afmformats' JPK reader with a faster ``.properties`` parser: the same records, ~5x sooner.

Reading a JPK force map through ``afmformats.load_data`` spends two thirds of its time in
``jprops.load_properties`` (a character-by-character Java properties parser), and parses the
shared header three times (two format detections, then the load). This module runs
afmformats' own :class:`~afmformats.formats.fmt_jpk.jpk_reader.JPKReader` (conversions,
metadata recipes, lazy columns: all afmformats') with two changes:

* :func:`load_properties` gives exactly ``jprops.load_properties``'s dict (same keys, values and
  order): plain lines split by jprops' rules in a few string operations, a line with a
  backslash by jprops' own functions, and a text with a continued line by jprops itself;
* the format detection is not repeated: afmforce found the JPK archive already, and the
  modality is the reader's :meth:`get_imaging_mode` (what afmformats' ``detect`` returns).

:func:`load_jpk_data` is ``afmformats.load_data`` for a JPK file (``fmt_jpk.load_jpk`` and
the ``AFMData`` wrapping, kept line for line). Any exception sends the caller back to
``afmformats.load_data``, which reads (or refuses) the file as before; a test compares the
records (columns and metadata) with afmformats' on every JPK file at hand.
"""

from __future__ import annotations

import functools
import io
import math
import pathlib
import re
import string
from typing import Any, Callable, Mapping

import numpy as np

__all__ = ["load_properties", "load_jpk_data"]

#: jprops' key terminators: = : and ASCII whitespace (string.whitespace)
_TERMINATOR = re.compile("[=:" + re.escape(string.whitespace) + "]")


def load_properties(raw: bytes) -> dict[str, str]:
    """``jprops.load_properties`` of a ``.properties`` file's bytes, faster.

    jprops' rules for a line without backslashes: latin-1 text, universal newlines, leading
    (Unicode) whitespace stripped, blank lines and ``#``/``!`` comments skipped; the key runs to
    the first ``=``, ``:`` or ASCII whitespace, the value is the rest, left-stripped (after a
    whitespace terminator, one ``=`` or ``:`` and the space after it are skipped too).
    """
    text = raw.decode("latin-1")
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    props: dict[str, str] = {}
    for line in lines:
        if line.endswith("\\") and (len(line) - len(line.rstrip("\\"))) % 2:
            import jprops  # a continued line (comments too): jprops reads the whole text

            return jprops.load_properties(io.BytesIO(raw))
        body = line.lstrip()
        if not body or body[0] in "#!":
            continue
        if "\\" in body:  # escapes: jprops' own key split and unescaping of this line
            import jprops

            key, value = jprops._split_key_value(body)
            props[jprops._unescape(key)] = jprops._unescape(value)
            continue
        m = _TERMINATOR.search(body)
        if m is None:
            key, value = body, ""
        else:
            i, c = m.start(), m.group()
            key, value = body[:i], body[i + 1:].lstrip()
            if c not in "=:" and value[:1] in ("=", ":"):
                value = value[1:].lstrip()
        props[key] = value
    return props


@functools.lru_cache(maxsize=1)
def _reader_class():
    """A JPKReader whose three property readers use :func:`load_properties` (built on first use:
    afmformats is imported only when a JPK file is read)."""
    from afmformats.formats.fmt_jpk import jpk_meta
    from afmformats.formats.fmt_jpk.jpk_reader import ArchiveCache, JPKReader

    def _read(path, name):
        return load_properties(ArchiveCache.get(path).read(name))

    def _read_once(reader, name):
        """A copy of the parsed file, parsed once per reader (a curve's index header is read for
        each of its segments)."""
        cache = reader.__dict__.setdefault("_afmforce_props", {})
        if name not in cache:
            cache[name] = _read(reader.path, name)
        return dict(cache[name])

    class FastJPKReader(JPKReader):
        @property
        @functools.lru_cache()
        def _properties_general(self):
            return _read(self.path, "header.properties")

        @property
        @functools.lru_cache()
        def _properties_shared(self):
            path = "shared-data/header.properties"
            return _read(self.path, path) if path in self.files else {}

        @property
        @functools.lru_cache()
        def _shared_groups(self):
            """Shared keys ``a.b.rest`` by ``(a, b)``, each group in sorted order, with ``rest``: the keys
            afmformats' loop finds with ``k2.startswith(f"{a}.{b}.")`` (for ``b`` without a dot)."""
            groups = {}
            for k2 in sorted(self._properties_shared.keys()):
                parts = k2.split(".", 2)
                if len(parts) == 3:
                    groups.setdefault((parts[0], parts[1]), []).append((k2, parts[2]))
            return groups

        @functools.lru_cache()
        def _get_index_segment_properties(self, index, segment):
            # afmformats 0.18.7 JPKReader._get_index_segment_properties, jprops replaced
            prop = _read_once(self, self.get_index_path(index) + "header.properties")
            if segment is not None:
                prop.update(_read_once(self, self.get_index_segment_path(index, segment)
                                       + "segment-header.properties"))
            psprop = self._properties_shared
            proplist = sorted(prop.keys())
            pslist = sorted(psprop.keys())
            groups = self._shared_groups
            for key in proplist:
                if key.count(".*"):
                    pindex = prop[key]
                    mediator = ".".join(key.split(".")[-2:-1])
                    headkey = key.rsplit(".", 2)[0]
                    if "." not in pindex:  # the shared keys "<mediator>.<pindex>.<var>", in sorted order
                        for k2, var in groups.get((mediator, pindex), ()):
                            prop[".".join([headkey, var])] = psprop[k2]
                        continue
                    startid = "{}.{}.".format(mediator, pindex)
                    for k2 in pslist:
                        if k2.startswith(startid):
                            var = ".".join(k2.split(".")[2:])
                            prop[".".join([headkey, var])] = psprop[k2]
            prop.update(self._properties_general)
            for p in list(prop.keys()):
                v = prop[p]
                if isinstance(v, str) and v[:1].isalpha() and v[:1] not in "iInN":
                    continue  # float() refuses a text starting with a letter other than inf/nan's
                try:
                    prop[p] = float(v)
                except BaseException:
                    pass
                else:
                    if math.isnan(prop[p]):
                        prop.pop(p)
            prmet = jpk_meta.get_primary_meta_recipe()
            for key, base_slot, unit in [("spring constant", "distance", "N"), ("sensitivity", "volts", "m")]:
                if key in self._user_metadata:
                    for opt_mult in prmet[key]:
                        prop[opt_mult] = self._user_metadata[key]
                        opt_off = opt_mult.rsplit(".", 1)[0] + ".offset"
                        prop[opt_off] = 0
                        opt_unit = opt_mult.rsplit(".", 1)[0] + ".unit"
                        prop[opt_unit] = unit
                        opt_slot = (opt_mult.rsplit(".", 2)[0] + ".base-calibration-slot")
                        prop[opt_slot] = base_slot
            return prop

    return FastJPKReader


def load_jpk_data(path: pathlib.Path, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list:
    """``afmformats.load_data(path, meta_override=...)`` for a JPK archive, with the fast reader.

    Raises whatever afmformats' reader raises; the caller then calls ``afmformats.load_data``.
    """
    from afmformats.formats import default_data_classes_by_modality, formats_by_suffix
    from afmformats.formats.fmt_jpk import load_jpk
    from afmformats.lazy_loader import LazyData
    from afmformats.meta import LazyMetaValue

    path = pathlib.Path(path)
    recipes = formats_by_suffix.get(path.suffix, [])
    if len(recipes) != 1 or recipes[0].loader is not load_jpk:
        raise ValueError(f"not a JPK suffix: {path.suffix}")
    recipe = recipes[0]
    # fmt_jpk.load_jpk with the fast reader
    jpkr = _reader_class()(path)
    jpkr.set_metadata(dict(meta_override))
    dataset = []
    for index in range(len(jpkr)):
        lazy_data = LazyData()
        for column in ["force", "height (measured)", "height (piezo)", "segment", "time"]:
            lazy_data.set_lazy_loader(column=column, func=jpkr.get_data, kwargs={"column": column, "index": index})
        metadata = jpkr.get_metadata(index=index)
        metadata["z range"] = LazyMetaValue(lambda data: np.ptp(data["height (piezo)"]), lazy_data)
        dataset.append({"data": lazy_data, "metadata": metadata})
        if callback:
            callback((1 + index) / len(jpkr))
    # load_data: the recipe's format name, the modality's data class (afmformats' detect gives
    # the modality from a reader without the user's metadata: it does not depend on it)
    cls = default_data_classes_by_modality[jpkr.get_imaging_mode()]
    out = []
    for dd in dataset:
        dd["metadata"]["format"] = "{} ({})".format(recipe["maker"], recipe["descr"])
        out.append(cls(data=dd["data"], metadata=dd["metadata"], diskcache=False))
    return out
