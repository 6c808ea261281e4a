"""CCSDS Attitude Ephemeris Message (AEM 2.0) export through the ``ccsds-ndm`` package.

One AEM per satellite (:func:`write_aems`), built from the package's AEM 2.0 data
model (``ccsds_ndm.models.ndmxml4``) and written as NDM/XML by its ``NdmIo`` (the
KVN writer of ccsds-ndm 3.1 leaves QUATERNION/ANGVEL data lines empty, so XML is the
format the package writes and re-reads without loss). Content of each file:

* ``REF_FRAME_A = TEME``, ``REF_FRAME_B = SC_BODY_1``: the quaternion rotates TEME
  axes onto body axes, i.e. it is the library's body -> TEME attitude quaternion
  (:mod:`jaxspline.planner.attitude_laws`), written as ``Q1 Q2 Q3`` (vector) and ``QC``
  (scalar);
* ``ATTITUDE_TYPE = QUATERNION/ANGVEL``, ``ANGVEL_FRAME = SC_BODY_1``: body rates in
  deg/s (the unit the standard prescribes);
* ``TIME_SYSTEM = UTC``; epochs are the scenario epoch plus the sample times, printed
  to 1 ns; numbers are printed with Python's shortest round-trip repr (17 significant
  digits at most), so re-reading gives back exactly the written doubles;
* the samples of :func:`jaxspline.products.attitude_history.attitude_history` (the step grid
  plus every junction instant), ``INTERPOLATION_METHOD = HERMITE``, degree 3
  (quaternion and rate at both ends of an interval).
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from pathlib import Path

import numpy as np

from jaxspline.planner.files import atomic_write_text, refuse_overwrite

__all__ = ["aem_file_name", "read_aem", "write_aems"]

_NS_DIGITS = 9  # decimals of the epoch seconds (1 ns)
_INTERPOLATION_DEGREE = 3
_ORIGINATOR = "jaxspline"
_SAFE_NAME = re.compile(r"[^A-Za-z0-9_.-]+")


def aem_file_name(sat_name: str) -> str:
    """``attitude_<name>.aem.xml`` with characters other than ``[A-Za-z0-9_.-]`` as ``_``.

    Args:
      sat_name: satellite name.
    Returns:
      str, the file name.
    """
    return f"attitude_{_SAFE_NAME.sub('_', sat_name)}.aem.xml"


def _epoch(epoch: _dt.datetime, seconds: float) -> str:
    """ISO-8601 UTC of ``epoch + seconds``, seconds printed to 1 ns."""
    whole = math.floor(seconds)
    frac = seconds - whole
    day = epoch + _dt.timedelta(seconds=whole)
    digits = f"{frac:.{_NS_DIGITS}f}"
    if digits.startswith("1"):  # rounding reached the next second
        day, digits = day + _dt.timedelta(seconds=1), f"{0.0:.{_NS_DIGITS}f}"
    return day.strftime("%Y-%m-%dT%H:%M:%S") + digits[1:] + "Z"


def _object_id(sat) -> str:
    """International designator (YYYY-NNNP) from a TLE's line 1, else the name."""
    if isinstance(sat.orbit, tuple | list) and isinstance(sat.orbit[0], str):
        cospar = sat.orbit[0][9:17].strip()
        if len(cospar) >= 5 and cospar[:2].isdigit():
            yy = int(cospar[:2])
            return f"{1900 + yy if yy >= 57 else 2000 + yy}-{cospar[2:]}"
    return sat.name


def _aem_document(scenario, sat_index: int, history, *, created: _dt.datetime | None = None):
    """The ``ccsds_ndm`` AEM object of one satellite's :class:`AttitudeHistory`.

    Args:
      scenario: Scenario (epoch, satellite names).
      sat_index: int, index of the satellite in ``scenario.satellites``.
      history: AttitudeHistory of that satellite (times [s from the epoch], q, ω).
      created: creation date of the header; None: now (UTC).
    Returns:
      ``ccsds_ndm`` Aem (quaternion scalar first, body to TEME; rates in deg/s).
    """
    from ccsds_ndm.models.ndmxml4 import Aem
    from ccsds_ndm.models.ndmxml4.ndmxml_4_0_0_aem_2_0 import (
        AemBody,
        AemData,
        AemMetadata,
        AemSegment,
    )
    from ccsds_ndm.models.ndmxml4.ndmxml_4_0_0_common_4_0 import (
        AdmHeader,
        AngleRateUnits,
        AngVelComponentType,
        AngVelType,
        AttitudeStateType,
        AttitudeTypeType,
        QuaternionAngVelType,
        QuaternionType,
    )

    sat = scenario.satellites[sat_index]
    t = np.asarray(history.t, np.float64)
    if t.size < 2:
        raise ValueError(f"history.t: an AEM needs at least 2 samples, got {t.size}")
    q = np.asarray(history.q, np.float64)
    w = np.degrees(np.asarray(history.omega, np.float64))

    def rate(x):
        return AngVelComponentType(value=float(x), units=AngleRateUnits.DEG_S)

    states = [
        AttitudeStateType(
            quaternion_ang_vel=QuaternionAngVelType(
                epoch=_epoch(scenario.epoch, float(t[i])),
                quaternion=QuaternionType(
                    q1=float(q[i, 1]), q2=float(q[i, 2]), q3=float(q[i, 3]), qc=float(q[i, 0])
                ),
                ang_vel=AngVelType(
                    angvel_x=rate(w[i, 0]), angvel_y=rate(w[i, 1]), angvel_z=rate(w[i, 2])
                ),  # fmt: skip
            )
        )
        for i in range(t.size)
    ]
    meta = AemMetadata(
        comment=[
            f"jaxspline plan of scenario {scenario.name}: scan laws, degree-7 MRP joins, nadir",
            "quaternion body (SC_BODY_1: +Z boresight, +X image motion) to TEME; rates deg/s",
        ],
        object_name=sat.name,
        object_id=_object_id(sat),
        center_name="EARTH",
        ref_frame_a="TEME",
        ref_frame_b="SC_BODY_1",
        time_system="UTC",
        start_time=_epoch(scenario.epoch, float(t[0])),
        stop_time=_epoch(scenario.epoch, float(t[-1])),
        attitude_type=AttitudeTypeType.QUATERNION_ANGVEL_1,
        angvel_frame="SC_BODY_1",
        interpolation_method="HERMITE",
        interpolation_degree=_INTERPOLATION_DEGREE,
    )
    when = created or _dt.datetime.now(_dt.UTC)
    header = AdmHeader(creation_date=when.strftime("%Y-%m-%dT%H:%M:%SZ"), originator=_ORIGINATOR)
    return Aem(
        header=header,
        body=AemBody(segment=[AemSegment(metadata=meta, data=AemData(attitude_state=states))]),
    )


def write_aems(result, attitude, outdir, *, force: bool = False) -> list[Path]:
    """Write one AEM per satellite of ``attitude`` (:func:`attitude_history`) into ``outdir``.

    File names: :func:`aem_file_name`. Atomic; every name is checked before anything
    is written.

    Args:
      result: PlanResult.
      attitude: PlanAttitude of the plan (its ``histories`` by satellite name).
      outdir: str or Path, created if missing.
      force: overwrite existing files.
    Returns:
      list of the written paths.
    Raises:
      FileExistsError: a file exists and ``force`` is false.
    """
    from ccsds_ndm.mapping import NDMFileFormats
    from ccsds_ndm.ndm_io import NdmIo

    sc = result.scenario
    out = Path(outdir)
    paths = [out / aem_file_name(s.name) for s in sc.satellites]
    for p in paths:
        refuse_overwrite(p, force)
    io = NdmIo()
    for k, (s, p) in enumerate(zip(sc.satellites, paths, strict=True)):
        doc = _aem_document(sc, k, attitude.histories[s.name])
        atomic_write_text(p, io.to_string(doc, NDMFileFormats.XML), force=True)
    return paths


def read_aem(path):
    """Re-read an AEM through ``ccsds-ndm``.

    Args:
      path: str or Path of an AEM XML file.
    Returns:
      ``(object name, epochs str [N], q float [N, 4], ω float [N, 3])``: ``q`` scalar
      first (as the library), ``ω`` [rad/s] body axes.
    """
    from ccsds_ndm.ndm_io import NdmIo

    doc = NdmIo().from_path(path)
    seg = doc.body.segment[0]
    rows = [s.quaternion_ang_vel for s in seg.data.attitude_state]
    q = np.array(
        [[r.quaternion.qc, r.quaternion.q1, r.quaternion.q2, r.quaternion.q3] for r in rows]
    )
    w = np.array([[r.ang_vel.angvel_x.value, r.ang_vel.angvel_y.value, r.ang_vel.angvel_z.value]
                  for r in rows])  # fmt: skip
    return seg.metadata.object_name, [r.epoch for r in rows], q, np.radians(w)
