"""Force-curve families afmforce knows but does not read: one clear refusal each.

A file whose ending no reader claims would otherwise get "unknown file type" and a list of
endings; a user holding a Nanosurf ``.nhf`` or an NT-MDT ``.mdt`` learns more from the format's
name and what to do with it (export the curves to a format afmforce reads, or read the instrument's
own file). :func:`unread_refusal` gives that line. These endings are not claimed
(:func:`afmforce.io.is_supported` stays False), so a folder given to ``afmforce analyze`` skips them.
The TIFF endings are claimed by the Park reader (``park-tiff``); a TIFF it does not recognise (any
other TIFF: an image) gets its line here too, through :func:`afmforce.io.find_format`.
"""

from __future__ import annotations

import struct
from pathlib import Path

_EXPORT = "export the curves in a format `afmforce formats` lists, or as afmforce raw text (docs/formats.md)"

#: ending -> (format, why afmforce does not read it, what to do)
UNREAD: dict[str, tuple[str, str, str]] = {
    ".nhf": ("Nanosurf NHF file (HDF5, Nanosurf Studio / DriveAFM)",
             "no reader for it yet; the public NHF files found hold images or WaveMode NMA maps, e.g. nanosurf-apps "
             "2.0.7's example: per pixel one averaged 20 kHz off-resonance period of 150 deflection samples, "
             "no measured z per sample",
             "save the curves as .nid from the Nanosurf software (read by 'nanosurf-nid'), or " + _EXPORT),
    ".mdt": ("NT-MDT MDT binary file (Nova)",
             "no public MDT force-curve file with a usable licence was found to test a reader against",
             "export the curves from Nova as text (three columns: read by 'ntmdt-txt'), or " + _EXPORT),
    ".gsi": ("WSxM force volume (.gsi, a 3D curve grid)",
             "only WSxM's force-curve series (.curves) are read",
             "save the curves from WSxM as a .curves series (read by 'wsxm-curves'), or " + _EXPORT),
    ".cur": ("WSxM text curve (.cur)", "only WSxM's force-curve series (.curves) are read",
             "save the curves from WSxM as a .curves series (read by 'wsxm-curves'), or " + _EXPORT),
    ".stp": ("WSxM image (.stp)", "it is an image, not a force curve",
             "give the force curves of the session (.curves)"),
    ".tiff": ("a TIFF file", "", ""),
    ".tif": ("a TIFF file", "", ""),
    ".uff": ("PyFMReader UFF text file (a re-saved curve)",
             "it has no time column, and one made from a Bruker file keeps the approach in that file's order "
             "(turning point first) and gives the ramp rate as its sampling rate",
             "read the instrument file it was made from"),
    ".gwy": ("Gwyddion file (.gwy)", "it is Gwyddion's own container of images and processed graphs, "
             "without the instrument's calibration (spring constant, sensitivity, ramp)",
             "read the instrument's own file of the curves, or " + _EXPORT),
    ".jpk": ("JPK image file", "it is an image, not a force curve",
             "give the force curves (.jpk-force, .jpk-force-map, .jpk-qi-data)"),
    ".jpk-qi-image": ("JPK QI image file", "it holds the maps computed from a QI measurement, not the curves",
                      "give the curves (.jpk-qi-data)"),
    ".h5-jpk": ("JPK HDF5 file (.h5-jpk, JPK SPM software 8)",
                "no public .h5-jpk force-curve file was found to test a reader against (the one found, "
                "AFMReader's sample, holds images)",
                "save the curves from the JPK software as .jpk-force, .jpk-force-map or .jpk-qi-data, or " + _EXPORT),
    ".asd": ("high-speed AFM movie (.asd)", "it holds image frames, not force curves",
             "give the force curves of the session"),
    ".topostats": ("TopoStats file (.topostats)", "it holds images processed by TopoStats, not force curves",
                   "give the instrument's force-curve files"),
    ".top": ("WSxM image (.top)", "it is an image, not a force curve",
             "give the force curves of the session (.curves)"),
    ".mat": ("MATLAB data file (.mat)", "it holds what a MATLAB program saved, without a force file's layout "
             "or calibration", "read the instrument's own file of the curves, or " + _EXPORT),
    ".3ds": ("Nanonis grid spectroscopy file (.3ds)", "it holds STM/nc-AFM sweeps (bias or z) of a Nanonis "
             "controller, not the deflection-versus-z ramps of a force curve",
             "export contact-mode force curves in a format `afmforce formats` lists, or as afmforce raw text "
             "(docs/formats.md)"),
    ".sxm": ("Nanonis image (.sxm)", "it is an image, not a force curve",
             "give the force curves of the session"),
    ".gsf": ("Gwyddion Simple Field (.gsf)", "it is an image (one height field), not a force curve",
             "give the force curves of the session"),
    ".axz": ("Anasys (Bruker nanoIR) file (.axz, gzipped XML)", "it holds images and IR spectra, not force "
             "curves afmforce can calibrate", "read the instrument's own file of the curves, or " + _EXPORT),
}

#: Park Systems' private TIFF tags (XEI): the magic number and the header block
_PARK_MAGIC, _PARK_HEADER = 50432, 50435


def _tiff_tags(path: Path) -> tuple[str, dict[int, tuple[int, int, int]]]:
    """The byte order and the first IFD's tags (tag -> (type, count, value or offset)); {} if not a TIFF."""
    with open(path, "rb") as fh:
        head = fh.read(8)
        if head[:4] not in (b"II*\x00", b"MM\x00*"):
            return "<", {}
        end = "<" if head[:2] == b"II" else ">"
        (ifd,) = struct.unpack(end + "I", head[4:8])
        fh.seek(ifd)
        raw = fh.read(2)
        if len(raw) < 2:
            return end, {}
        (n,) = struct.unpack(end + "H", raw)
        block = fh.read(12 * min(n, 4096))
    tags = {}
    for i in range(len(block) // 12):
        tag, typ, count, value = struct.unpack(end + "HHII", block[12 * i:12 * i + 12])
        tags[tag] = (typ, count, value)
    return end, tags


def _park_kind(path: Path, end: str, tags: dict) -> str:
    """'spectroscopy', 'line profile' or 'image' from the Park header's first int (its data type)."""
    try:
        _, count, offset = tags[_PARK_HEADER]
        with open(path, "rb") as fh:
            fh.seek(offset)
            raw = fh.read(4)
        kind = struct.unpack(end + "i", raw)[0]
    except (KeyError, OSError, struct.error):
        return ""
    return {0: "image", 1: "line profile", 2: "spectroscopy"}.get(kind, "")


def _is_tiff(path: Path) -> bool:
    """Whether the file starts with a TIFF signature (``II*\\0`` or ``MM\\0*``)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(4) in (b"II*\x00", b"MM\x00*")
    except OSError:
        return False


def _tiff(path: Path) -> tuple[str, str, str]:
    try:
        end, tags = _tiff_tags(path)
    except (OSError, struct.error):
        end, tags = "<", {}
    if _PARK_MAGIC in tags:
        kind = _park_kind(path, end, tags)
        what = f"Park Systems TIFF file (XEI{', ' + kind + ' data' if kind else ''})"
        if kind in ("image", "line profile"):
            return what, f"it holds {'an' if kind == 'image' else 'a'} {kind}, not a force curve", \
                "give the spectroscopy file of the measurement"
        return what, "its Park magic number (TIFF tag 50432) is not Park's value 0x0E031301: damaged", \
            "read the spectroscopy file as saved by the Park software (reader 'park-tiff')"
    return ("TIFF image", "it is an image, not a force curve", "give the force-curve file of the measurement")


def _uff_source(path: Path) -> str:
    """The instrument file a UFF file names (``HE Entry_filename:``), or ''."""
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as fh:
            for _, line in zip(range(200), fh):
                if line.startswith("HE Entry_filename:"):
                    return line.split(":", 1)[1].strip().strip('"')
    except OSError:
        pass
    return ""


#: The first line of a Git LFS pointer: what a clone without Git LFS holds in place of a large file
#: (public repositories of AFM data keep their .jpk-qi-data, .ARDF and .spm maps so).
LFS_POINTER = b"version https://git-lfs.github.com/spec/"


def lfs_pointer_refusal(path: str | Path) -> str | None:
    """The one-line refusal of a Git LFS pointer file (any ending), or None: the file the pointer stands for
    was not downloaded, so no reader can recognise it (they said "content not recognised ... name its reader")."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(1024)
    except OSError:
        return None
    if not head.startswith(LFS_POINTER):
        return None
    fields = dict(line.split(" ", 1) for line in head.decode("latin-1").splitlines() if " " in line)
    size = fields.get("size", "").strip()
    oid = fields.get("oid", "").strip()
    stands = f"the {int(size):,}-byte file" if size.isdigit() else "a file"
    return (f"{path}: a Git LFS pointer ({len(head)} bytes) standing for {stands}"
            f"{' (' + oid[:19] + '...)' if oid else ''}, not the data: the repository was cloned or "
            "downloaded without Git LFS; fetch the file itself (`git lfs pull` in the clone) and give that")


def unread_refusal(path: str | Path) -> str | None:
    """The one-line refusal of a file of a family afmforce does not read, or None.

    Parameters
    ----------
    path : str or Path
        A file whose ending no reader claims.
    """
    path = Path(path)
    name = path.name.lower()
    suffix = next((s for s in sorted(UNREAD, key=len, reverse=True) if name.endswith(s)), None)
    if suffix is None:
        return None
    if suffix in (".tiff", ".tif") and not _is_tiff(path):
        return None     # not a TIFF at all (no signature): never named "a TIFF image"
    what, why, todo = _tiff(path) if suffix in (".tiff", ".tif") else UNREAD[suffix]
    if suffix == ".uff":
        source = _uff_source(path)
        if source:
            todo += f" ({source})"
    article = "an" if what[:1] in "AEIOU" or what.startswith("NT-") else "a"
    return f"{path}: {article} {what}, a format afmforce does not read ({why}): {todo}"


#: file start -> (the family it opens, the identifiers of its readers in ``FORMATS``, whose endings it should
#: bear): a damaged or cut file of a known family, or one under another family's ending (:func:`damaged_refusal`)
MAGIC: dict[bytes, tuple[str, tuple[str, ...]]] = {
    b"PK\x03\x04": ("a zip archive (JPK force file)", ("jpk-force",)),
    b"\x89HDF\r\n\x1a\n": ("an HDF5 file", ("afmforce-hdf5", "afmformats-hdf5")),
    b"\\*Force file list": ("a Bruker NanoScope force file", ("bruker-nanoscope",)),
    b"ARDF": ("an Asylum ARDF file", ("asylum-ardf",)),
    b"[DataSet]": ("a Nanosurf .nid file", ("nanosurf-nid",)),
    b"WSxM file copyright": ("a WSxM file", ("wsxm-curves",)),
    b"II*\x00": ("a TIFF file", ("park-tiff",)),
    b"MM\x00*": ("a TIFF file", ("park-tiff",)),
    b"\x05\x00": ("an Igor binary wave", ("asylum-ibw",)),
}
_AGAIN = "a truncated download or copy, or a disk that filled up: copy the file again from the instrument's computer"


def damaged_refusal(path: str | Path) -> str | None:
    """The line for a file that starts like a family afmforce reads (:data:`MAGIC`) but that no reader
    recognises: under another family's ending (a renamed file), cut short (a zip without its central
    directory at the end) or damaged; None for a file of no known family."""
    path = Path(path)
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(64)
            fh.seek(max(0, size - 65558))   # a zip's end record (22 bytes + a comment of at most 64 KiB)
            tail = fh.read()
    except OSError:
        return None
    found = next((v for magic, v in MAGIC.items() if head.startswith(magic)), None)
    if found is None:
        return None
    from . import FORMATS

    family, readers = found
    readers = [FORMATS[r] for r in readers if r in FORMATS]
    endings = list(dict.fromkeys([e for f in readers for e in f.suffixes]
                                 + [".000-.999" for f in readers if f.pattern]))
    if readers and not any(f.claims(path.name) for f in readers):
        return (f"{path}: its first bytes are those of {family}, not of a file of the ending "
                f"'{path.suffix}': renamed? give it its own ending ({', '.join(endings)})")
    if head.startswith(b"PK\x03\x04"):
        if b"PK\x05\x06" not in tail:
            return (f"{path}: {family} cut short: its table of contents at the end is missing ({size} bytes); "
                    + _AGAIN)
        import zipfile

        try:
            with zipfile.ZipFile(path) as arc:
                bad = arc.testzip()
        except Exception as exc:  # noqa: BLE001  any failure of the archive is its damage
            bad = f"{type(exc).__name__}: {str(exc)[:120]}"
        return None if bad is None else (f"{path}: damaged {family[2:]}: {bad} fails its checksum or does not "
                                         "decompress; " + _AGAIN)
    if head.startswith(b"\x89HDF"):
        try:
            import h5py

            with h5py.File(path, "r"):
                return None    # a whole HDF5 file of another program: not damaged, only not recognised
        except ImportError:
            return None
        except Exception:  # noqa: BLE001  h5py cannot open it: cut or damaged
            pass
    return (f"{path}: starts as {family}, but the rest of its content is not recognised ({size} bytes): cut short "
            f"or damaged ({_AGAIN}), or a variant afmforce does not read (name its reader as `format` to see "
            "what it finds wrong)")
