"""The adapter to the lab: capture files, calibration, bundles and serial device triggers.

* :func:`read_cube`, :func:`read_array`, :func:`write_cube` — cubes and arrays in MATLAB (v5 and
  v7.3), HDF5, NumPy, ENVI and multi-page TIFF files, by extension (:mod:`~tensor_cosdi.io.files`).
* :func:`load_frames`, :func:`read_frame` — TIFF / PNG / JPEG / NPY / NPZ / MAT frames, dark and
flat
  correction, region of interest, binning, gap detection.
* :func:`frames_to_measurement`, :func:`measurement_to_frames` — sensor frames ↔ each system's
measurement.
* :func:`calibrate_lenslet_grid` → :class:`LensletGrid` (pitch, offset, rotation, views).
* :func:`code_from_monochromator`, :func:`shifts_from_line_frames` — a measured code per band and
  the dispersion (Appendix A); :func:`estimate_registration` — the mask's offset on the sensor
  (and the dispersion direction, for unevenly spaced shifts) from a capture alone.
* :func:`save_bundle`, :func:`load_bundle` — one file with the data, the system, calibration and
provenance.
* :class:`AcquisitionPlan`, :class:`SerialDevice`, :class:`Acquisition`
(:mod:`tensor_cosdi.io.triggers`) —
  acquisition plans sent to a trigger device over a serial port, with a resumable frame log.
"""

from ._atomic import atomic_write
from .bundle import Bundle, file_digest, load_bundle, save_bundle, system_from_state, system_state
from .calibration import (
    Registration,
    code_from_monochromator,
    estimate_registration,
    mirror_symmetric,
    shifts_from_line_frames,
)
from .files import read_array, read_cube, split_key, write_cube
from .frames import (
    FRAME_SUFFIXES,
    bin_frame,
    crop,
    frame_paths,
    load_frames,
    read_frame,
    write_frames,
)
from .layouts import dual_camera_frames, frame_count, frames_to_measurement, measurement_to_frames
from .lenslet import LensletGrid, calibrate_lenslet_grid
from .triggers import (
    Acquisition,
    AcquisitionPlan,
    DeviceError,
    FakeTriggerDevice,
    FolderCamera,
    SerialDevice,
    Step,
    read_log,
)

__all__ = [
    "atomic_write",
    "read_cube",
    "read_array",
    "write_cube",
    "split_key",
    "read_frame",
    "write_frames",
    "load_frames",
    "bin_frame",
    "crop",
    "frame_paths",
    "FRAME_SUFFIXES",
    "frames_to_measurement",
    "measurement_to_frames",
    "frame_count",
    "dual_camera_frames",
    "calibrate_lenslet_grid",
    "LensletGrid",
    "save_bundle",
    "load_bundle",
    "Bundle",
    "file_digest",
    "system_state",
    "system_from_state",
    "code_from_monochromator",
    "shifts_from_line_frames",
    "estimate_registration",
    "mirror_symmetric",
    "Registration",
    "Acquisition",
    "AcquisitionPlan",
    "DeviceError",
    "FakeTriggerDevice",
    "FolderCamera",
    "SerialDevice",
    "Step",
    "read_log",
]
