"""The :class:`Robust` attitude filter and smoother (exported as ``imukit.filters.Robust``).

=====================  ===========================================================================
estimate               ``R_wb`` as a scipy ``Rotation`` in ``world="ENU"`` or ``"NED"`` (as the other
                       filters, ``imukit.filters``)
accelerometer          specific force, low-passed in an almost-inertial frame (short accelerations
                       cancel there) before it corrects the inclination
magnetometer (9D)      heading only, never the inclination; disturbed samples (norm, dip against a
                       learned reference) rejected for a bounded time
gyro_bias              Kalman estimate after each sample [rad/s], with ``gyro_bias_sigma``
offline                ``run(..., offline=True)``: forward and backward passes' biases fused, the
                       specific force filtered forward then backward (zero phase, acausal)
=====================  ===========================================================================

Every default is the Rust core's ``RobustParams::default()`` (``imukit._core.RobustParams()``).
Equations, literature and measured accuracy and speed: ``docs/filters_robust.md``.
"""

from __future__ import annotations

import threading
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray, flag, real_scalar, rotation_from_unit_quat
from imukit._errors import ParameterError
from imukit.filters import WORLDS, _check_mag_norms, _initial_quat, _Locked, _run_mag, _vec3
from imukit.imu import ImuData
from imukit.threads import checked

__all__ = ["Robust", "RobustResult", "RobustState"]

PARAMS: dict[str, float] = dict(_core.RobustParams().fields())


class RobustState(_core.RobustState):
    """A saved :class:`Robust` state: immutable, pickles and deep-copies exactly. Fields by name
    (``fields()``); read ``rotation``, ``quaternion`` (xyzw), ``gyro_bias``, ``gyro_bias_sigma``
    [rad/s], ``initialized``, ``time``."""

    __slots__ = ()

    def __new__(cls, state: _core.RobustState | None = None, /, **fields: Any) -> RobustState:
        if state is not None:
            if not isinstance(state, _core.RobustState):
                raise ParameterError(f"expected a RobustState, got {type(state).__name__}", argument="state")
            return super().__new__(cls, state, **fields)  # a copy; with fields, the core refuses
        return super().__new__(cls, **fields)

    def __repr__(self) -> str:
        q, b = self.quaternion.tolist(), self.gyro_bias.tolist()
        return f"RobustState(quaternion={q!r}, gyro_bias={b!r}, time={self.time!r}, initialized={self.initialized!r})"

    @property
    def rotation(self) -> Rotation:
        """The attitude ``R_wb``."""
        return Rotation.from_quat(self.quaternion)


class RobustResult(NamedTuple):
    """Output of :meth:`Robust.run`: the fields of ``imukit.filters.FilterResult`` (``rotation``,
    ``gyro_bias`` (N, 3), ``state`` after the last sample) plus per sample ``gyro_bias_sigma``
    (N, 3) [rad/s], ``rest`` (N,) and ``mag_disturbed`` (N,) flags."""

    rotation: Rotation
    gyro_bias: FloatArray
    state: RobustState
    gyro_bias_sigma: FloatArray
    rest: np.ndarray
    mag_disturbed: np.ndarray


class Robust(_Locked):
    """Attitude filter that holds under sustained and short accelerations (after Laidig & Seel,
    Information Fusion 91, 2023): gyro strapdown into an almost-inertial frame, the specific force
    low-passed there (2nd-order Butterworth) corrects the inclination, a Kalman filter estimates the
    gyro bias (rest and motion), and the magnetometer corrects the heading only, with disturbance
    rejection. ``run(..., offline=True)`` smooths the whole record.

    Parameters (keyword-only; defaults from the Rust core, units in the names: ``_s`` seconds,
    ``_rad`` radians, ``_rad_s`` rad/s; see ``docs/filters_robust.md``)
    ----------
    world
        ``"ENU"`` (default) or ``"NED"``.
    **params
        Any field of ``imukit._core.RobustParams`` (``Robust.DEFAULTS`` lists them with their
        defaults), e.g. ``tau_acc_s``, ``tau_mag_s``, ``mag_dip_rad``.
    """

    DEFAULTS = PARAMS

    def __init__(self, *, world: str = "ENU", **params: float) -> None:
        if not isinstance(world, str):  # the core checks the name
            raise ParameterError(f"expected one of {WORLDS}, got {world!r}", argument="world")
        for name, value in params.items():
            params[name] = real_scalar(value, name, what="a real number", accept=lambda x: True)
        self.params = _core.RobustParams(**params)
        self._core_filter = _core.RobustFilter(self.params, world)
        self._world = world
        self._lock = threading.Lock()
        self.reset()

    def __getattr__(self, name: str) -> float:
        if name in PARAMS:
            return float(self.params.fields()[name])
        raise AttributeError(name)

    @property
    def world(self) -> str:
        """``"ENU"`` or ``"NED"`` (canonical name)."""
        return str(self._core_filter.__getnewargs__()[1])

    def reset(self, initial: Rotation | None = None) -> None:
        """Forget the state; the next :meth:`update` initialises (or, from ``initial``, is a step
        of its ``dt``, ``initial``'s heading in 9D replaced by the first field sample's: north is
        the field's; ``run(imu, initial=R)`` instead outputs ``R`` for its first sample)."""
        self._state = RobustState(self._core_filter.initial_state(_initial_quat(initial)))

    def get_state(self) -> RobustState:
        """The current streaming state (immutable; keep it to restore later)."""
        return self._state

    def set_state(self, state: RobustState) -> None:
        """Restore a state from :meth:`get_state` or ``run(...).state``."""
        if not isinstance(state, RobustState):
            raise ParameterError(f"expected a RobustState, got {type(state).__name__}", argument="state")
        self._state = state

    def update(self, gyro: ArrayLike, accel: ArrayLike, dt: float, mag: ArrayLike | None = None) -> Rotation:
        """One streaming sample (``dt`` [s] since the previous one; ignored on the first, which
        initialises); returns the current attitude ``R_wb``. ``mag=None``: within ``mag_hold_s``
        (default 1 s) of the last field sample, that sample turned by the gyro stands in, so the
        heading loop and the field's gate run in seconds whatever the field's rate
        (``mag_hold_s=0``: no field then)."""
        w, a = _vec3(gyro, "gyro"), _vec3(accel, "accel")
        step = real_scalar(dt, "dt", what="a step in seconds", accept=lambda x: True)
        m = None if mag is None else _check_mag_norms(np.array([_vec3(mag, "mag")]))[0].tolist()
        with self._lock:
            self._state = state = RobustState(self._core_filter.update(self._state, w, a, step, m))
        return rotation_from_unit_quat(state.quaternion)

    def run(
        self,
        imu: ImuData,
        *,
        mag: ArrayLike | bool | None = None,
        initial: Rotation | RobustState | None = None,
        offline: bool = False,
        threads: int | None = None,
    ) -> RobustResult:
        """Filter (or, ``offline=True``, smooth) a whole recording natively with the GIL released
        (Ctrl-C stops an online run within ~65,536 samples, the smoother in its first stage or after
        its second);
        the streaming state is not touched. ``imu``'s arrays are read in place; a ``mag=`` array
        that Python code could write to meanwhile is copied first (5–12 ns/sample at 10^6 samples:
        pass the field as ``ImuData(..., mag=...)`` to save it).

        ``threads``: the run takes two (online from 1024 samples: each step's bias-window sums,
        heading loop and output on the second; offline: the passes side by side); None: the
        process setting (:func:`imukit.set_num_threads`); 1 runs everything on one. The result is
        the same on any number. The second thread polls while it waits (an online run takes about
        twice its wall time in CPU): with as many processes as cores, each running filters, pass 1.

        ``mag``: as ``Mahony.run``'s: None → ``imu.mag`` when there is one (9D); ``False`` → 6D;
        ``True`` → ``imu.mag``, which must be there; an ``(N, 3)`` array → those samples.
        ``initial``: None (the first sample initialises), a ``Rotation`` (the attitude at
        ``imu.t[0]``; in 9D its heading lasts until the field's first sample after it gives the
        field's, north being the field's), or a :class:`RobustState` to continue from (online only; the first sample is
        a step of ``imu.t[0] − state.time``). The result's ``state`` is the forward pass's last.
        """
        if not isinstance(imu, ImuData):
            raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
        offline = flag(offline, "offline")
        threads = checked(threads)
        mags = _run_mag(imu, mag)
        if mags is not None:
            _check_mag_norms(mags)
        continued = isinstance(initial, RobustState)
        if isinstance(initial, RobustState):
            if offline:
                raise ParameterError("the smoother starts from a Rotation or None, not a state", argument="initial")
            start = initial._at_time(initial.time - float(imu.t[0]))  # the core's clock is imu.seconds
        else:
            start = self._core_filter.initial_state(_initial_quat(initial, "RobustState"))
        q, bias, sigma, rest, disturbed, final = self._core_filter.run(
            imu.seconds, imu.gyro, imu.accel, mags, start, continued, offline, threads
        )
        state = RobustState(final._at_time(float(imu.t[-1])))
        return RobustResult(rotation_from_unit_quat(q), bias, state, sigma, rest, disturbed)
