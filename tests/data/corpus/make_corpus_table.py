"""Write ``corpus.json``: each corpus file's header values read WITHOUT afmforce.

Run from the repository root: ``python tests/data/corpus/make_corpus_table.py``. The values come
from the files' own text: JPK archives through ``zipfile`` and a plain ``key=value`` split of their
``.properties`` headers; Asylum waves through igor2 (the wave note); Bruker NanoScope files from the
header text (the ``Deflection Error`` image list); text exports from their header lines and their
rows counted. Nothing here imports afmforce: ``tests/io/test_corpus_gallery.py`` compares what
afmforce reads with these numbers. The provenance (repository, path, commit, licence) and the
expected outcome of each file are kept in ``SOURCES`` below and copied into the table.
"""

from __future__ import annotations

import json
import re
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

COMMITS = {
    "AFM-analysis/afmformats": "731b5ad88bbb99b2455694d29016acd85a731388",
    "pycroscopy/SciFiDatasets": "0c977f2f0db47514f3b0c0c79ad698ddc8fddd71",
    "DyNaMo-INSERM/PyFMlab_DyNaMo": "73cd0f6b4af0fa896b5a444d10d95fa7463291c2",
    "galvanetto/Fodis": "e1af81f09b667ba51a8840dc8ee493d98567acf1",
    "jcbs/ForceMetric": "da100476581856522cfd66c5ea7328c7baf3a282",
    "ilyasku/jpkfile": "ccde5ac33a76cf893211295f678dc304ff2b1c0d",
    "bicarlsen/jpk_reader": "e9486d42bf89a8b36a8d2ef4c6e3bbd885571352",
    "HoseynAAmiri/pyrtz2": "016ef73e7ccc88305f3186f7a8f2e9931b9e8560",
    "CellMechLab/softmech": "d94b9dc40d11032b11596fd116c2e24703b6474d",
    "JSotres/FSAS-ForceSpectroscopyAnalysisSoftware-MatLab": "a319f85ffa43993f313c3e301a26a7a0798cc030",
}

#: file -> (family, repository, path in it (zip member after ":"), licence)
SOURCES = {
    "afm-workshop_mapping-16_13.07.00.csv": ("AFM Workshop CSV", "AFM-analysis/afmformats", "tests/data/fmt-afm-workshop-fd_mapping_16_2018-08-01_13.07.zip:AFM-workshop_FD_mapping_16_2018-08-01_13.07.00.csv", "MIT"),
    "afm-workshop_single_2020-02-14.csv": ("AFM Workshop CSV", "AFM-analysis/afmformats", "tests/data/fmt-afm-workshop-fd_single_2020-02-14_13.41.25.csv", "MIT"),
    "afm-workshop_single_2021-01-15.csv": ("AFM Workshop CSV", "AFM-analysis/afmformats", "tests/data/fmt-afm-workshop-fd_single_2021-01-15.csv", "MIT"),
    "afm-workshop_single_2021-10-22.csv": ("AFM Workshop CSV", "AFM-analysis/afmformats", "tests/data/fmt-afm-workshop-fd_single_2021-10-22_14.16.csv", "MIT"),
    "afmformats-hdf5_v0.13.3_jpk-force-save.h5": ("afmformats HDF5 export (v0.13.3, of a JPK CellHesion curve)", "AFM-analysis/afmformats", "tests/data/fmt-hdf5-fd_version_0.13.3.h5", "MIT"),
    "afmformats-tab_v0.13.3_jpk-force-save.tab": ("afmformats tab export (v0.13.3, of a JPK CellHesion curve, cropped)", "AFM-analysis/afmformats", "tests/data/fmt-tab-fd_version_0.13.3.tab", "MIT"),
    "afm-workshop_volts_2018-08-01.csv": ("AFM Workshop CSV", "AFM-analysis/afmformats", "tests/data/fmt-afm-workshop-fd_single_2018-08-01_13.06.09.csv", "MIT"),
    "asylum-ibw_AR16_dwell-10s_cell37m0000.ibw": ("Asylum .ibw (AR 16.05, MFP-3D, 10 s dwell)", "HoseynAAmiri/pyrtz2", "data/example/label1val1label2val1cell37m0000.ibw", "MIT"),
    "asylum-ibw_AR16_dwell-10s_cell39m0000.ibw": ("Asylum .ibw (AR 16.05, MFP-3D, 10 s dwell)", "HoseynAAmiri/pyrtz2", "data/example/label1val3label2val3cell39m0000.ibw", "MIT"),
    "asylum-ibw_Cypher_AR15_PFM-mode_LRCol0_MS_LG7d0001.ibw": ("Asylum .ibw (Cypher, AR 15.09, ImagingMode 'PFM Mode', 5 channels)", "jcbs/ForceMetric", "Examples/LRCol0_MS_LG7d0001.ibw", "MIT"),
    "asylum-ibw_ForceMetric_X60_3_x4_0100.ibw": ("Asylum .ibw", "jcbs/ForceMetric", "Examples/Data/X60_3_x4_0100.ibw", "MIT"),
    "asylum-ibw_ForceMetric_X60_3_x4_0120.ibw": ("Asylum .ibw", "jcbs/ForceMetric", "Examples/Data/X60_3_x4_0120.ibw", "MIT"),
    "asylum-ibw_ForceMetric_X60_3_x4_0146.ibw": ("Asylum .ibw", "jcbs/ForceMetric", "Examples/Data/X60_3_x4_0146.ibw", "MIT"),
    "asylum-ibw_SiN_FD_plot.ibw": ("Asylum .ibw", "AFM-analysis/afmformats", "tests/data/fmt-igor-fd_SiN_FD_plot.ibw", "MIT (noted CC0 there)"),
    "asylum-ibw_U3_3_p10004.ibw": ("Asylum .ibw", "AFM-analysis/afmformats", "tests/data/fmt-igor-fd_U3_3_p10004.ibw", "MIT"),
    "asylum-ibw_no-date_ForceMap.ibw": ("Asylum .ibw (from an ARDF force map)", "pycroscopy/SciFiDatasets", "data/microscopy/spm/afm/IgorIBWReader_ForceCurve.ibw", "MIT"),
    "bruker-ascii_fodis_ScanAsyst-glass.txt": ("NanoScope Analysis export", "galvanetto/Fodis", "Datasets/Bruker example files/ScanAsystOnGlass.0_00009.spm.txt", "Apache-2.0"),
    "bruker-ascii_fodis_ScanAsyst-glass_retract.txt": ("NanoScope Analysis export (processed)", "galvanetto/Fodis", "Datasets/Bruker example files/ScanAsystOnGlass.0_00009.spm -retract curve.txt", "Apache-2.0"),
    "bruker-ascii_fodis_extracted.txt": ("NanoScope Analysis export (processed)", "galvanetto/Fodis", "Datasets/Bruker example files/Bruker_extracted_file1.txt", "Apache-2.0"),
    "bruker-ascii_fodis_mica-GA6_baseline-corrected.txt": ("NanoScope Analysis export (processed)", "galvanetto/Fodis", "Datasets/Bruker example files/Mica in DDW with GA6 2.8.17.0_00000.spm-CD58_ForceCurveIndex_2294BaseLine Correction_1.spm - NanoScope Analysis.txt", "Apache-2.0"),
    "bruker-nanoscope_force-volume_v9.2_Egel2_00023.spm": ("Bruker NanoScope binary (force volume)", "DyNaMo-INSERM/PyFMlab_DyNaMo", "PyFMReader_DyNaMo/tests/testfiles/20200903_Egel2.0_00023.spm", "MIT"),
    "bruker-nanoscope_v8.15_Bruker-example_Force.spm": ("Bruker NanoScope binary (Bruker's own example)", "PyPI nanoscope 1.2.300", "nanoscope/Example Nanoscope Files/Force.spm", "Apache-2.0"),
    "bruker-nanoscope_v9.30_Bruker-example_ForceHold.spm": ("Bruker NanoScope binary (force hold: extend, 0.1 s hold, retract; Bruker's own example)", "PyPI nanoscope 1.2.300", "nanoscope/Example Nanoscope Files/ForceHold.spm", "Apache-2.0"),
    "bruker-nanoscope_v9.40_Bruker-example_ForceHoldSweep.spm": ("Bruker NanoScope binary (force hold with amplitude and phase channels; Bruker's own example)", "PyPI nanoscope 1.2.300", "nanoscope/Example Nanoscope Files/ForceHoldSweep.spm", "Apache-2.0"),
    "bruker-nanoscope_v8.15_MultiMode_FSAS_mica-air_Test.000": ("Bruker NanoScope binary (MultiMode, mica in air; its DeflSens 1.38 x the contact slope's)", "JSotres/FSAS-ForceSpectroscopyAnalysisSoftware-MatLab", "SampleFiles/Test.000", "BSD 2-Clause"),
    "bruker-nanoscope_v8.15_sapphire_TAP525.001": ("Bruker NanoScope binary", "pycroscopy/SciFiDatasets", "data/microscopy/spm/afm/BrukerReader_ForceCurve_Sapphire_TAP525.001", "MIT"),
    "bruker-nanoscope_v9.2_Egel4_00025.spm": ("Bruker NanoScope binary", "DyNaMo-INSERM/PyFMlab_DyNaMo", "PyFMReader_DyNaMo/tests/testfiles/20200904_Egel4-Z1.0_00025.spm", "MIT"),
    "chiaro-txt_V3.4.1_displacement-hold.txt": ("Optics11 Chiaro text (V3.4.1, displacement profile with a 1 s hold)", "CellMechLab/softmech", "optics11_new_new.txt", "MIT"),
    "chiaro-txt_AEBP1_Indentation_002.txt": ("Optics11 Chiaro text", "AFM-analysis/afmformats", "tests/data/fmt-chiaro-txt_AEBP1_Indentation_002.zip:fmt-chiaro-txt_AEBP1_Indentation_002.txt", "MIT"),
    "jpk-dp_float-data_SMFS_0441.jpk-force": ("JPK re-saved by JPK DP (float data)", "galvanetto/Fodis", "Datasets/JPK example files/jpk-force/force-save-0441.jpk-force", "Apache-2.0"),
    "jpk-dp_float-data_SMFS_0578.jpk-force": ("JPK re-saved by JPK DP (float data)", "galvanetto/Fodis", "Datasets/JPK example files/jpk-force/force-save-0578.jpk-force", "Apache-2.0"),
    "jpk-dp_float-data_SMFS_1126.jpk-force": ("JPK re-saved by JPK DP (float data)", "galvanetto/Fodis", "Datasets/JPK example files/jpk-force/force-save-1126.jpk-force", "Apache-2.0"),
    "jpk-force-map_2x2.jpk-force-map": ("JPK force map", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_map2x2_extracted.jpk-force-map", "MIT"),
    "jpk-force-map_HeLa_4x4.jpk-force-map": ("JPK force map", "DyNaMo-INSERM/PyFMlab_DyNaMo", "PyFMRheo_DyNaMo/tests/testfiles/map-data-2022.10.29-12.27.34.564.jpk-force-map", "MIT"),
    "jpk-force-map_map0d.jpk-force-map": ("JPK force map", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_map0d_extracted.jpk-force-map", "MIT"),
    "jpk-force-map_microrheology_4x4.jpk-force-map": ("JPK force map (modulation segments)", "DyNaMo-INSERM/PyFMlab_DyNaMo", "PyFMReader_DyNaMo/tests/testfiles/map-data-2021.11.05-17.37.44.432.jpk-force-map", "MIT"),
    "jpk-force-map_reference-points.jpk-force-map": ("JPK force map", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_map-data-reference-points.jpk-force-map", "MIT"),
    "jpk-force_calibration_2015.jpk-force": ("JPK .jpk-force (CellHesion)", "AFM-analysis/afmformats", "tests/data/fmt-jpk-cl_calibration_force-save-2015.02.04-11.25.21.294.jpk-force", "MIT"),
    "jpk-force_cellhesion200_2016.jpk-force": ("JPK .jpk-force (CellHesion)", "ilyasku/jpkfile", "examples/force-save-2016.06.15-13.17.08.jpk-force", "MIT"),
    "jpk-force_cellhesion_spot3.jpk-force": ("JPK .jpk-force", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_spot3-0192.jpk-force", "MIT"),
    "jpk-force_creep-compliance_brain.jpk-force": ("JPK .jpk-force (CellHesion)", "AFM-analysis/afmformats", "tests/data/fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force", "MIT"),
    "jpk-force_creep-compliance_polymergel.jpk-force": ("JPK .jpk-force (CellHesion)", "AFM-analysis/afmformats", "tests/data/fmt-jpk-cc_pr14-polymergel-2021.06.30.jpk-force", "MIT"),
    "jpk-force_flipsign_2015.jpk-force": ("JPK .jpk-force", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force", "MIT"),
    "jpk-force_force-save-example.jpk-force": ("JPK .jpk-force (CellHesion)", "AFM-analysis/afmformats", "docs/data/force-save-example.jpk-force", "MIT"),
    "jpk-force_no-spring-constant_2023.jpk-force": ("JPK .jpk-force", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_single-modified_2023.jpk-force", "MIT"),
    "jpk-force_stress-relaxation_cell1-0001.jpk-force": ("JPK .jpk-force", "AFM-analysis/afmformats", "examples/data/10.1002_btm2.10294_fig5d-cell1.zip:cell1-0001.jpk-force", "MIT"),
    "jpk-force_stress-relaxation_cell1-0008.jpk-force": ("JPK .jpk-force", "AFM-analysis/afmformats", "tests/data/fmt-jpk-sr_cell1-0008.jpk-force", "MIT"),
    "jpk-qi-data_2020.02.07.jpk-qi-data": ("JPK QI data", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data", "MIT"),
    "jpk-qi-data_v8.1_format-2.0.jpk-qi-data": ("JPK QI data (SPM 8.1.64, file format 2.0)", "bicarlsen/jpk_reader", "data/qi_data/qi_data-2_0-xs/ (the archive's 234 members, published unzipped; zipped here, bytes unchanged)", "MIT"),
    "jpk-qi-series_2021.04.13.jpk-qi-series": ("JPK QI series", "AFM-analysis/afmformats", "tests/data/fmt-jpk-fd_qi-data-2021.04.13.jpk-qi-series", "MIT"),
    "jpk-txt_dp-export_SMFS_0441.txt": ("JPK DP text export", "galvanetto/Fodis", "Datasets/JPK example files/txt exported/force-save-0441.txt", "Apache-2.0"),
    "jpk-txt_spm6.1_creep-compliance_JPK00556_index62.txt": ("JPK SPM 6.1 text export (CellHesion 200, creep compliance: extend, pause, retract)", "AFM-analysis/afmformats", "tests/data/example2_creep.txt", "MIT"),
    "jpk-txt_spm6.1_creep-compliance_JPK01466_index7.txt": ("JPK SPM 6.1 text export (CellHesion 200, creep compliance: extend, pause, retract)", "AFM-analysis/afmformats", "tests/data/example1_creep.txt", "MIT"),
    "ntmdt-txt_gel4_Curve_DFL_Height_51.txt": ("NT-MDT Nova text", "AFM-analysis/afmformats", "tests/data/fmt-ntmdt-txt-fd_2015_01_17_gel4-0,1_mQ_adh_6B_Curve_DFL_Height_51.txt", "MIT"),
    "wsxm-curves_spectrocurve_0001_Normalforce.f.curves": ("WSxM curves (Nanotec)", "pycroscopy/SciFiDatasets", "data/microscopy/spm/afm/wsxm/WSxM1DReader_spectrocurve_0001_Normalforce.f.curves", "MIT"),
}

#: sources that are not git repositories: the SHA-1 of the published archive stands for the commit
#: (``sha1sum nanoscope-1.2.300-py2.py3-none-any.whl``, Bruker's wheel on PyPI, Apache-2.0)
COMMITS["PyPI nanoscope 1.2.300"] = "a64456866b3e68e88e8db7df1757e2761b1ecb7b"

#: files taken from another commit than the repository's in COMMITS (a pull request's head)
FILE_COMMITS = {
    "chiaro-txt_V3.4.1_displacement-hold.txt": "b193b42ba1e31464145b0952f574d0d360ef2056",  # removed by 584de05
    "wsxm-curves_spectrocurve_0001_Normalforce.f.curves": "eabc7a708e316bdf19cd344c603f014b99c3daea",
    "asylum-ibw_Cypher_AR15_PFM-mode_LRCol0_MS_LG7d0001.ibw": "54649d12785f1c506188fdcb87d12d799160fef5",  # removed later
    # afmformats pull request 14 (issue 9, "added example creep files"); removed from it by b55004f
    "jpk-txt_spm6.1_creep-compliance_JPK00556_index62.txt": "85676d0271dec3df10c56a82aef9938bf97125b8",
    "jpk-txt_spm6.1_creep-compliance_JPK01466_index7.txt": "85676d0271dec3df10c56a82aef9938bf97125b8",
}

#: what the file lacks and a user gives (stand-ins; the gallery passes them as meta_override)
GIVEN = {
    "afm-workshop_mapping-16_13.07.00.csv": {"spring_constant": 0.1, "sensitivity": 50e-9},
    "afm-workshop_single_2021-01-15.csv": {"spring_constant": 0.1, "sensitivity": 50e-9},
    "afm-workshop_volts_2018-08-01.csv": {"spring_constant": 0.1, "sensitivity": 50e-9},
    "ntmdt-txt_gel4_Curve_DFL_Height_51.txt": {"spring_constant": 0.05, "sensitivity": 61e-9},
    "jpk-force_calibration_2015.jpk-force": {"spring_constant": 0.05, "sensitivity": 50e-9},
    "jpk-force_no-spring-constant_2023.jpk-force": {"spring_constant": 12.0},
}

#: files another part of issue 32 will read right; until then the gallery expects them to fail
#: (xfail, strict: the lead flips them at merge). "read": the reader; "analysis": the numbers.
PENDING_READ: dict[str, str] = {}
PENDING_ANALYSIS = {
    **PENDING_READ,
}


def _props(raw: bytes) -> dict[str, str]:
    """A ``.properties`` file by the simplest rule: ``key=value`` lines, ``\\:`` unescaped."""
    out = {}
    for line in raw.decode("latin-1").splitlines():
        if line.startswith("#") or "=" not in line:
            continue
        key, value = line.split("=", 1)
        out[key.strip()] = value.strip().replace("\\:", ":")
    return out


def _jpk_curve(arc: zipfile.ZipFile, names: list, shared: dict, prefix: str) -> dict:
    """One curve's segments (type, points, name, duration) and vDeflection's calibration."""
    seg_ids = sorted({int(m.group(1)) for n in names
                      if (m := re.match(re.escape(prefix) + r"segments/(\d+)/segment-header", n))})
    segs, k, s = [], None, None
    for sid in seg_ids:
        h = _props(arc.read(f"{prefix}segments/{sid}/segment-header.properties"))
        ref = h.get("force-segment-header.force-segment-header-info.*")
        if ref is not None:
            h.update({"force-segment-header." + key.split(".", 2)[2]: v for key, v in shared.items()
                      if key.startswith(f"force-segment-header-info.{ref}.")})
        style = h.get("force-segment-header.settings.style") or h.get(
            "force-segment-header.settings.segment-settings.type", "?")
        name = h.get("force-segment-header.settings.segment-settings.identifier.name", "")
        n = int(h.get("force-segment-header.num-points") or h["channel.vDeflection.data.num-points"])
        segs.append([style, n, name, float(h.get("force-segment-header.duration", "nan"))])
        lcd = h.get("channel.vDeflection.lcd-info.*")
        src = {k2.split(".", 2)[2]: v for k2, v in shared.items() if k2.startswith(f"lcd-info.{lcd}.")} if lcd else {}
        src.update({k2[len("channel.vDeflection."):]: v for k2, v in h.items() if k2.startswith("channel.vDeflection.")})
        c = "conversion-set.conversion."
        if src.get(c + "force.defined") == "true":
            k = float(src[c + "force.scaling.multiplier"])
        if src.get(c + "distance.defined") == "true":
            s = float(src[c + "distance.scaling.multiplier"])
    # a CellHesion pause-at-start segment is stored last and happens first
    first = [x for x in segs if "pause-at-start" in x[2]]
    segs = first + [x for x in segs if x not in first]
    ext = next((x for x in segs if "extend" in x[0]), None)
    rate = ext[1] / ext[3] if ext and ext[3] > 0 else None
    return {"k": k, "s": s, "rate": rate, "segments": [[t, n] for t, n, _, _ in segs]}


def _jpk(path: Path) -> dict:
    with zipfile.ZipFile(path) as arc:
        names = arc.namelist()
        shared = _props(arc.read("shared-data/header.properties")) if "shared-data/header.properties" in names else {}
        if any(n.startswith("segments/") for n in names):
            prefixes = [""]
        else:
            idx = sorted({int(m.group(1)) for n in names if (m := re.match(r"index/(\d+)/segments/", n))})
            prefixes = [f"index/{i}/" for i in idx]
        curves = [_jpk_curve(arc, names, shared, p) for p in prefixes]
    out = {"spring_constant": curves[0]["k"], "sensitivity": curves[0]["s"], "sample_rate": curves[0]["rate"],
           "curves": len(curves), "segments": curves[0]["segments"]}
    if len(curves) > 1:  # a map's curves differ where an extend stopped at the trigger
        out["per_curve"] = [{"sample_rate": c["rate"], "segments": c["segments"]} for c in curves]
    return out


#: files whose every curve is a hard adhesive contact the tip leaves with one clean jump (seen on the raw
#: curves): the pull-off force the analysis must give is read from the raw retract, below
PULL_OFF = {"jpk-qi-data_v8.1_format-2.0.jpk-qi-data"}


def _jpk_pull_off(path: Path) -> list[float]:
    """Each curve's pull-off force [N] from the raw vDeflection: the integers decoded by the shared
    ``lcd-info`` encoder, times the distance and force multipliers; the deepest retract sample before
    its largest single-sample rise (the tip springing off), less the median of the approach's first
    half (the free baseline)."""
    out = []
    with zipfile.ZipFile(path) as arc:
        shared = _props(arc.read("shared-data/header.properties"))
        idx = sorted({int(m.group(1)) for n in arc.namelist() if (m := re.match(r"index/(\d+)/segments/", n))})
        for i in idx:
            force = []
            for seg in (0, 1):
                h = _props(arc.read(f"index/{i}/segments/{seg}/segment-header.properties"))
                p = f"lcd-info.{h['channel.vDeflection.lcd-info.*']}."
                c = {k[len(p):]: float(v) for k, v in shared.items() if k.startswith(p) and k.endswith(
                    ("encoder.scaling.multiplier", "encoder.scaling.offset", "distance.scaling.multiplier",
                     "force.scaling.multiplier"))}
                raw = np.frombuffer(arc.read(f"index/{i}/segments/{seg}/channels/vDeflection.dat"), ">i4")
                volts = raw * c["encoder.scaling.multiplier"] + c["encoder.scaling.offset"]
                force.append(volts * c["conversion-set.conversion.distance.scaling.multiplier"]
                             * c["conversion-set.conversion.force.scaling.multiplier"])
            ext, ret = force
            jump = int(np.argmax(np.diff(ret)))
            out.append(float(ret[: jump + 1].min() - np.median(ext[: ext.size // 2])))
    return out


def _ibw(path: Path) -> dict:
    from igor2 import binarywave

    wave = binarywave.load(path)["wave"]
    note = {}
    for line in wave["note"].decode("latin-1").replace("\n", "\r").split("\r"):
        if ":" in line:
            key, value = line.split(":", 1)
            note.setdefault(key.strip(), value.strip())
    n = wave["wData"].shape[0]
    idx = [int(v) for v in note["Indexes"].split(",") if v.strip()]
    dirs = [v.strip() for v in note.get("Direction", "").split(",") if v.strip()][1:]
    words = {"1": "extend", "-1": "retract", "0": "dwell"}
    segs = [[words[d], b - a] for (a, b), d in zip(zip(idx, idx[1:]), dirs)]
    segs[-1][1] += n - idx[-1]  # Indexes end at the last sample's index
    return {"spring_constant": float(note["SpringConstant"]), "sensitivity": float(note["InvOLS"]),
            "sample_rate": float(note["NumPtsPerSec"]), "curves": 1, "segments": segs,
            "date": note.get("Date")}


def _nanoscope(path: Path) -> dict:
    text = path.read_bytes()[:200_000].decode("latin-1")
    text = text[:text.index("File list end")]
    lists = text.split("\\*")
    defl = next(b for b in lists if b.startswith("Ciao force image list") and "Deflection Error" in b)
    k = float(re.search(r"\\Spring Constant: ([\d.eE+-]+)", defl).group(1))
    s = float(re.search(r"\\@Sens. DeflSens: V ([\d.eE+-]+)", text).group(1)) * 1e-9
    force_list = next(b for b in lists if b.startswith("Ciao force list"))
    ext, ret = (int(v) for v in re.search(r"\\Samps/line: (\d+) (\d+)", defl).groups())
    scan = float(re.search(r"\\Scan rate: ([\d.eE+-]+)", force_list).group(1))
    grid = re.search(r"Ciao scan list.*?\\Samps/line: (\d+)", text, re.S).group(1)
    fv = "force-volume" in path.name
    segs = [["extend", ext], ["retract", ret]]
    hold = re.search(r"\\Hold Samples: (\d+)", force_list)
    length = int(re.search(r"\\Data length: (\d+)", defl).group(1))
    if hold and int(hold.group(1)) and any(length == (ext + ret + int(hold.group(1))) * b for b in (2, 4)):
        segs.insert(1, ["hold", int(hold.group(1))])  # a force hold: its samples stored after both runs
    return {"spring_constant": k, "sensitivity": s, "sample_rate": (ext + ret) * scan,
            "curves": int(grid) ** 2 if fv else 1, "segments": segs}


#: NanoScope Analysis exports of one plotted run (a unit row, no header): which run, read by eye from
#: the file name and the curve (the contact, the larger force, at the start: the retract)
ONE_RUN = {
    "bruker-ascii_fodis_ScanAsyst-glass_retract.txt": "retract",
    "bruker-ascii_fodis_extracted.txt": "extend",
    "bruker-ascii_fodis_mica-GA6_baseline-corrected.txt": "retract",
}


def _bruker_ascii(path: Path) -> dict:
    """A NanoScope Analysis text export: the header as ``_nanoscope`` reads it, the rows counted."""
    text = path.read_bytes().decode("latin-1")
    rows = [ln for ln in text.replace("\r", "\n").split("\n") if ln.strip() and ln.strip()[0] in "-+.0123456789"]
    if path.name in ONE_RUN:  # no header: force in N, nothing else stored
        return {"spring_constant": None, "sensitivity": None, "sample_rate": None, "curves": 1,
                "segments": [[ONE_RUN[path.name], len(rows)]]}
    head = text[:text.lower().index("file list end")].replace('"', "")
    lists = head.split("\\*")
    defl = next(b for b in lists if b.startswith("Ciao force image list") and "Deflection Error" in b)
    k = float(re.search(r"\\Spring Constant: ([\d.eE+-]+)", defl).group(1))
    s = float(re.search(r"\\@Sens. DeflSens: V ([\d.eE+-]+)", head).group(1)) * 1e-9
    scan = float(re.search(r"\\Scan rate: ([\d.eE+-]+)", next(b for b in lists if b.startswith("Ciao force list"))).group(1))
    ext = sum(1 for r in rows if r.split("\t")[0].strip())  # every row has both runs here
    return {"spring_constant": k, "sensitivity": s, "sample_rate": 2 * len(rows) * scan, "curves": 1,
            "segments": [["extend", ext], ["retract", len(rows)]]}


def _jpk_text_segments(path: Path) -> list[tuple[str, dict[str, np.ndarray]]]:
    """Each ``# segment:`` block's columns (its ``# columns:`` names) as numpy arrays."""
    out, names, rows = [], [], None
    for line in path.read_text("latin-1").splitlines():
        if line.startswith("# segment:"):
            rows = []
            out.append((line.split(":", 1)[1].strip(), rows))
        elif line.startswith("# columns:"):
            names.append(line.split(":", 1)[1].split())
        elif line.strip() and not line.startswith("#") and rows is not None:
            rows.append([float(v) for v in line.split()])
    return [(seg, dict(zip(cols, np.array(rows, dtype=float).T))) for (seg, rows), cols in zip(out, names)]


def _jpk_text(path: Path) -> dict:
    """k and the sensitivity from the first segment's header lines; the sample rate from the extend's
    ``time`` column (1 / its median step); the rows of each segment counted."""
    k = s = None
    for line in path.read_text("latin-1").splitlines():
        if line.startswith("# springConstant:") and k is None:
            k = float(line.split(":", 1)[1])
        elif line.startswith("# sensitivity:") and s is None:
            s = float(line.split(":", 1)[1])
    segs = _jpk_text_segments(path)
    extend = next(cols for seg, cols in segs if seg == "extend")
    rate = 1.0 / float(np.median(np.diff(extend["time"])))
    return {"spring_constant": k, "sensitivity": s, "sample_rate": rate, "curves": 1,
            "segments": [[seg, len(next(iter(cols.values())))] for seg, cols in segs]}


#: JPK text exports whose adhesion the analysis must give (a deep, clean adhesion: -20 nN, noise 5 pN)
ADHESION = {"jpk-txt_spm6.1_creep-compliance_JPK01466_index7.txt"}


def _jpk_text_adhesion(path: Path) -> list[float]:
    """The adhesion force [N]: the retract's deepest vDeflection [N] less the baseline there, a straight
    line fitted against ``seriesTime`` to the retract's last half (the free tip drifting)."""
    ret = dict(_jpk_text_segments(path))["retract"]
    force, t = ret["vDeflection"], ret["seriesTime"]
    half = slice(force.size // 2, None)
    line = np.polyfit(t[half], force[half], 1)
    i = int(np.argmin(force))
    return [float(force[i] - np.polyval(line, t[i]))]


def _workshop(path: Path) -> dict:
    """AFM Workshop CSV: the extend and retract columns side by side, counted row by row."""
    ext = ret = 0
    for line in path.read_text("latin-1").splitlines():
        cells = line.strip().split(",")
        if len(cells) != 4:
            continue
        try:
            [float(c) for c in cells if c.strip()]
        except ValueError:
            continue  # the column names
        ext += bool(cells[0].strip() and cells[1].strip())
        ret += bool(cells[2].strip() and cells[3].strip())
    return {"spring_constant": None, "sensitivity": None, "sample_rate": None, "curves": 1,
            "segments": [["extend", ext], ["retract", ret]]}


def _chiaro(path: Path) -> dict:
    text = path.read_text("latin-1")
    k = float(re.search(r"k \(N/m\)\t([\d.]+)", text).group(1))
    return {"spring_constant": k, "sensitivity": None, "sample_rate": None, "curves": 1, "segments": None}


def _chiaro_modulus(path: Path) -> list[float]:
    """The Chiaro software's own Hertz fit of the curve: ``E[v=0.500] (Pa)`` (Poisson ratio 0.5, the
    header's tip radius), written in the export's header [Pa]."""
    text = path.read_text("latin-1")
    return [float(re.search(r"E\[v=0\.500\] \(Pa\)\t([\d.]+)", text).group(1))]


def _wsxm(path: Path) -> dict:
    """WSxM ``.curves``: the first header's Force constant and image size, then each curve block's header
    (its own ``Image header size``), counted; the rate is points over ``Forward plot total time``."""
    data = path.read_bytes()
    size = int(re.search(rb"Image header size: (\d+)", data).group(1))
    top = data[:size].decode("latin-1")
    k = float(re.search(r"Force constant: ([\d.eE+-]+) N/m", top).group(1))
    rows = int(re.search(r"Number of rows: (\d+)", top).group(1))
    cols = int(re.search(r"Number of columns: (\d+)", top).group(1))
    width = {"double": 8, "float-data": 4, "short": 2}[re.search(r"Image Data Type: (\S+)", top).group(1)]
    at, curves, rate, points = size + rows * cols * width, 0, None, None
    while at < len(data):
        hsize = int(re.search(rb"Image header size: (\d+)", data[at:at + 200]).group(1))
        head = data[at:at + hsize].decode("latin-1")
        points = int(re.search(r"Number of points: (\d+)", head).group(1))
        lines = int(re.search(r"Number of lines: (\d+)", head).group(1))
        ms = float(re.search(r"Forward plot total time: ([\d.]+) ms", head).group(1))
        rate = points / (ms * 1e-3)
        curves += lines // 2
        at += hsize + points * lines * 2 * width
    return {"spring_constant": k, "sensitivity": None, "sample_rate": rate, "curves": curves,
            "segments": [["extend", points], ["retract", points]]}


def _afmformats_export(path: Path) -> dict:
    """An afmformats export: the metadata (HDF5 attributes through h5py, or the tab file's JSON block), the
    points of each segment counted (HDF5 ``segment`` 0/1; tab ``segment`` column False/True)."""
    if path.suffix == ".h5":
        import h5py

        with h5py.File(path, "r") as h5:
            meta = dict(h5["0"].attrs)
            seg = h5["0/segment"][:].astype(int).tolist()
    else:
        text = path.read_text("latin-1")
        block = text[text.index("# BEGIN METADATA"):text.index("# END METADATA")].splitlines()[1:]
        meta = json.loads("\n".join(line[2:] for line in block))
        seg = [int(line.split("\t")[3] == "True") for line in text.splitlines() if line and not line.startswith("#")]
    return {"spring_constant": float(meta["spring constant"]), "sensitivity": float(meta["sensitivity"]),
            "sample_rate": float(meta["rate approach"]), "curves": 1,
            "segments": [["extend", seg.count(0)], ["retract", seg.count(1)]]}


def header(path: Path) -> dict:
    name = path.name
    if name.startswith("afmformats-"):
        return _afmformats_export(path)
    if name.startswith("wsxm-curves"):
        return _wsxm(path)
    if name.startswith(("jpk-force", "jpk-dp", "jpk-qi")):
        return _jpk(path)
    if name.endswith(".ibw"):
        return _ibw(path)
    if name.startswith("bruker-nanoscope"):
        return _nanoscope(path)
    if name.startswith("bruker-ascii"):
        return _bruker_ascii(path)
    if name.startswith("jpk-txt"):
        return _jpk_text(path)
    if name.startswith("chiaro"):
        return _chiaro(path)
    if name.startswith("afm-workshop"):
        return _workshop(path)
    return {"spring_constant": None, "sensitivity": None, "sample_rate": None, "curves": 1, "segments": None}


#: what an ``expected`` entry checks, in the README's words
CHECKED = {"pull_off_force": "pull-off of every curve", "youngs_modulus": "modulus (the Chiaro's own Hertz fit)",
           "adhesion_force": "adhesion (numpy on the retract column)"}


def _fmt(v, scale=1.0, digits=5):
    return "-" if v is None else f"{v * scale:.{digits}g}"


def readme(table: dict) -> str:
    """The corpus README: provenance, licence and the header values of every file."""
    lines = [
        "# Real-file corpus (issue 32)",
        "",
        "Public force-curve files as instruments and vendor software wrote them (never edited; a file",
        "taken out of a published zip archive is the member as published). Written by",
        "`make_corpus_table.py` (this table and `corpus.json`); tested by `tests/io/test_corpus_gallery.py`.",
        "Header values are read without afmforce: JPK archives through `zipfile` and the `.properties`",
        "text, Asylum waves through igor2, Bruker files from their header text, text exports from their",
        "header lines; `-`: the file does not store it (the gallery gives the stand-ins in `given`).",
        "",
        "Licences: MIT (afmformats (c) 2019 Paul Mueller; SciFiDatasets (c) 2021 pycroscopy; PyFMlab_DyNaMo",
        "(c) 2023 Javier Lopez Alonso; ForceMetric (c) 2018 Jacob Kienast; jpkfile (c) 2016 Ilyas Kuhlemann;",
        "pyrtz2 (c) 2024 Hoseyn Amiri; softmech (c) 2021 Massimo Vassalli; jpk_reader (c) 2025 Brian Carlsen, MIT or Apache-2.0 at the user's choice: MIT taken),",
        "BSD 2-Clause (FSAS (c) 2019 Javier Sotres, Malmoe University),",
        "and Apache-2.0 (Fodis, N. Galvanetto et al., Biophys. J. 114, 1264 (2018); the NanoScope Python Toolbox",
        "(c) 2021 Bruker Inc., PyPI `nanoscope` 1.2.300, whose wheel's SHA-1 stands for the commit),",
        "http://www.apache.org/licenses/LICENSE-2.0; files unchanged). The full licence texts are in",
        "`LICENSES`. Commits: "
        + "; ".join(f"{r} `{c[:10]}`" for r, c in COMMITS.items()) + "; "
        + "; ".join(f"`{n}` from `{c[:10]}`" for n, c in FILE_COMMITS.items()) + ".",
        "",
        "| file | family | bytes | k [N/m] | InvOLS [nm/V] | rate [Hz] | curves | segments (points) | expected | source (repository: path) | licence |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, e in table.items():
        h = e["header"]
        segs = ", ".join(f"{t} {n}" for t, n in h["segments"]) if h["segments"] else "-"
        exp = e["expect"]
        checked = "".join(f"; {CHECKED[k]} checked" for k in e.get("expected", {}))
        expect = "read, plausible" if exp == {"read": "read", "analysis": "plausible"} else (
            exp["read"] if exp["read"] != "read" else "read; analysis: " + exp["analysis"])
        lines.append(f"| `{name}` | {e['family']} | {e['bytes']} | {_fmt(h['spring_constant'])} | "
                     f"{_fmt(h['sensitivity'], 1e9)} | {_fmt(h['sample_rate'], 1, 6)} | {h['curves']} | {segs} | "
                     f"{expect}{checked} | {e['source']['repository']}: `{e['source']['path']}` | {e['source']['licence']} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    table = {}
    for name, (family, repo, src, licence) in sorted(SOURCES.items()):
        path = HERE / name
        entry = {"family": family, "bytes": path.stat().st_size,
                 "source": {"repository": repo, "path": src, "commit": FILE_COMMITS.get(name, COMMITS[repo]),
                            "licence": licence},
                 "header": header(path)}
        if name in GIVEN:
            entry["given"] = GIVEN[name]
        entry["expect"] = {"read": PENDING_READ.get(name, "read"), "analysis": PENDING_ANALYSIS.get(name, "plausible")}
        if name in PULL_OFF:  # numbers the analysis must give, per curve (test_corpus_gallery)
            entry["expected"] = {"pull_off_force": _jpk_pull_off(path)}
        if name in ADHESION:
            entry["expected"] = {"adhesion_force": _jpk_text_adhesion(path)}
        if name.startswith("chiaro-txt"):  # the instrument's Hertz modulus (test_corpus_gallery)
            entry["expected"] = {"youngs_modulus": _chiaro_modulus(path)}
        table[name] = entry
    (HERE / "corpus.json").write_text(json.dumps(table, indent=1) + "\n")
    (HERE / "README.md").write_text(readme(table))
    print(f"{len(table)} files, {sum(e['bytes'] for e in table.values()) / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
