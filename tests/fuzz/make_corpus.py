#!/usr/bin/env python3
"""Writes the seed corpus of the raster-import and CSV fuzz targets (tests/fuzz/corpus/).

Seeds of fuzz_import are small copies of the real fixtures (tests/data/dem), one per GDAL
driver the import documents, each in the container format of fuzz_import.cpp
(`<name>\\n<bytes>[\\0@@FILE@@<name>\\n<bytes>]...`): GeoTIFF (two fixtures as they are, the
polar stereographic Shoemaker DEM cut to 16 x 16), ISIS3 (three cubes cut small by GDAL, attached
labels), PDS4 (an XML label and its data file, written by GDAL) and PDS3 (the MOLA MEGDR's
detached label with its first 12 x 24 samples). Seeds of fuzz_csv_points are short CSV texts.
The store seeds come from make_store_seeds (a C++ program, built with the fuzz targets).

    python3 tests/fuzz/make_corpus.py [fixtures folder]
"""

import pathlib
import re
import sys
import tempfile

from osgeo import gdal

gdal.UseExceptions()
HERE = pathlib.Path(__file__).resolve().parent
FIXTURES = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "data" / "dem"
SEP = b"\0@@FILE@@"


def container(files):
    """files: [(name, bytes)], the raster first."""
    out = b""
    for k, (name, data) in enumerate(files):
        out += (SEP if k else b"") + name.encode() + b"\n" + data
    return out


def translate(src, fmt, size, tmp, name, options=()):
    dst = tmp / name
    gdal.Translate(str(dst), str(FIXTURES / src), format=fmt, width=size[0], height=size[1],
                   creationOptions=list(options))
    return dst


def import_seeds(out):
    with tempfile.TemporaryDirectory() as t:
        tmp = pathlib.Path(t)
        seeds = {
            "gtiff_unfinished": [("dem_unfinished.tif", (FIXTURES / "dem_unfinished.tif").read_bytes())],
            "gtiff_nodata_utm": [("dem_nodata.dem", (FIXTURES / "dem_nodata.dem").read_bytes())],
        }
        shoe = translate("Shoemaker_1k.tif", "GTiff", (16, 16), tmp, "shoemaker.tif")
        seeds["gtiff_polar"] = [("shoemaker.tif", shoe.read_bytes())]
        for key, src, size in [("isis3_lola", "ldem_4_reduced.cub", (24, 12)),
                               ("isis3_vesta", "vest64_dtm_specialpixels_downsampled.cub", (24, 12)),
                               ("isis3_hirise", "Ares4_Marth_Crater_3557E_126N_ngate_03_lowres.cub", (8, 23))]:
            cub = translate(src, "ISIS3", size, tmp, key + ".cub",
                            ["USE_SRC_LABEL=NO", "USE_SRC_HISTORY=NO", "ADD_GDAL_HISTORY=NO"])
            seeds[key] = [(cub.name, compact_isis3(cub.read_bytes()))]
        xml = translate("ldem_4_reduced.cub", "PDS4", (24, 12), tmp, "lola.xml")
        img = xml.with_suffix(".img")
        seeds["pds4_lola"] = [(xml.name, xml.read_bytes()), (img.name, img.read_bytes())]
        seeds["pds3_mola"] = pds3_seed()
    for key, files in seeds.items():
        (out / key).write_bytes(container(files))


def compact_isis3(cube):
    """GDAL's ISIS3 cube with its 64 KiB label area cut to the label's own length: StartByte
    and the Label's Bytes rewritten in place (same widths), the padding dropped."""
    start = int(re.search(rb"StartByte\s*=\s*(\d+)", cube).group(1))
    text_end = cube.index(b"\0")
    size = text_end + 64  # room for the longer numbers; GDAL pads with NULs
    label = cube[:start - 1]
    for key, value in [(rb"StartByte", size + 1), (rb"Bytes", size)]:
        m = re.search(key + rb"(\s*=\s*)(\d+ *)", label)
        field = str(value).encode().ljust(len(m.group(2)))
        label = label[:m.start(2)] + field + label[m.end(2):]
    return label[:size] + cube[start - 1:]


def pds3_seed():
    """The MEGDR label cut to its first 12 lines of 24 samples, and those samples."""
    label = (FIXTURES / "megt90n000cb.lbl").read_text(encoding="latin-1")
    rows, cols = 12, 24
    for key, value in [("FILE_RECORDS", rows), ("RECORD_BYTES", 2 * cols), ("LINES", rows),
                       ("LINE_SAMPLES", cols)]:
        label = re.sub(rf"(\n\s*{key}\s*=\s*)\d+", rf"\g<1>{value}", label)
    label = re.sub(r'"MEGT90N000CB.IMG"', '"mola.img"', label)
    image = (FIXTURES / "megt90n000cb.img").read_bytes()
    data = b"".join(image[r * 2880:r * 2880 + 2 * cols] for r in range(rows))
    return [("mola.lbl", label.encode("latin-1")), ("mola.img", data)]


CSV_SEEDS = {
    # first byte: the coordinates (0 lonlat, 1 grid, 2 xy), then the text as on stdin
    "lonlat_header": b"\0lon,lat\n137.4,-4.6\n-5.5,-2.05\n",
    "lonlat_comments": b"\0# points\n\n  +10.25 ,\t-89.999\r\n1e-3,90\n",
    "grid_header": b"\x01row,col\n0,0\n12.5,7.25\n",
    "xy_plain": b"\x02x,y\n-120.5,40\n3e2,-4E-1\n",
    "bad_header": b"\0lat,lon\n1,2\n",
    "bad_fields": b"\x02x,y,z\n1,2,3\n",
}


def main():
    corpus = HERE / "corpus"
    for target in ["fuzz_import", "fuzz_csv_points"]:
        (corpus / target).mkdir(parents=True, exist_ok=True)
    import_seeds(corpus / "fuzz_import")
    for key, text in CSV_SEEDS.items():
        (corpus / "fuzz_csv_points" / key).write_bytes(text)
    for target in ["fuzz_import", "fuzz_csv_points"]:
        files = sorted((corpus / target).iterdir())
        print(f"make_corpus: {target}: {len(files)} seeds, {sum(f.stat().st_size for f in files)} bytes")


if __name__ == "__main__":
    main()
