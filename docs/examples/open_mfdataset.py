"""Two runs of one scene opened as one dataset with ``xarray.open_mfdataset``.

    python docs/examples/open_mfdataset.py OUT        (or HDI_EXAMPLES_OUT=OUT python docs/examples/open_mfdataset.py)

The same small sweep at two DMW amplitudes (``dmw.rms_nm``), each in its own results folder
(``OUT/rms-0.2``, ``OUT/rms-0.3``), then both ``sweep.nc`` files side by side on a new dimension
``rms``: every variable keeps its units and dimensions. Writes only into the folder OUT.
"""

import json
import os
import sys
from pathlib import Path

import xarray as xr

import pipeline as hdi

#: The paper scene, by the name it is shipped under (works outside the clone: `load_scene` finds it in
#: the installed package)
PAPER = "paper-2009"
#: The paper scene, shortened: 0.6-ms runs, three protrusions [nm], fixed k.
TINY = ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.5",
        "sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}", "sweep.batch_size=3"]
RMS_NM = (0.2, 0.3)


def main(out: Path) -> dict:
    paths = []
    for rms in RMS_NM:
        scene = hdi.load_scene(PAPER, TINY + [f"dmw.rms_nm={rms}"])
        paths.append(hdi.run_stage("sweep", scene, out / f"rms-{rms}", scheduler="synchronous"))
    with xr.open_mfdataset(paths, combine="nested", concat_dim="rms", engine="netcdf4") as both:
        both = both.assign_coords(rms=("rms", list(RMS_NM), {"units": "nm", "long_name": "DMW rms"}))
        fhm = both["fhm_bv"].isel(roughness=0, damping=0).load()
        return {"dims": dict(both["fhm_bv"].sizes), "units": both["fhm_bv"].attrs["units"],
                "fhm_bv": fhm.values.tolist()}


if __name__ == "__main__":
    folder = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HDI_EXAMPLES_OUT")
    if not folder:
        sys.exit("usage: python docs/examples/open_mfdataset.py OUT (or set HDI_EXAMPLES_OUT): the folder to write into")
    print(json.dumps(main(Path(folder))))
