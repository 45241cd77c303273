"""sabodem from Python: scenarios, runs stepped or whole, the bodies as numpy arrays, the summary
as a dict. A thin ctypes layer over libsabodem.so and its driver API (include/sabodem_run.h);
docs/api.md explains it.

    import sabodem
    s = sabodem.Scenario.from_file("examples/flume_small.yaml", set={"dam.l_h": 0.05})
    with sabodem.Run(s, "out/study") as r:
        r.advance_phase()            # to the end of the packing
        b = r.bodies()               # numpy arrays: pos, vel, radius, shape, ...
        summary = r.run()            # to the end; summary.json as a dict
"""
import ctypes
import ctypes.util
import json
import os

import numpy as np

__all__ = ["Scenario", "Run", "ScenarioError", "RunError", "version", "library_path"]


class ScenarioError(ValueError):
    """A scenario that cannot be read: every message as file:line:col: message."""


class RunError(RuntimeError):
    """A run that cannot start or has failed."""


def _find_library():
    """$SABODEM_LIBRARY, else the library installed beside this package (PREFIX/lib), else the
    system's (ldconfig)."""
    env = os.environ.get("SABODEM_LIBRARY")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    # PREFIX/lib/python3.X/dist-packages/sabodem -> PREFIX/lib
    for up in ("../../..", "../../../.."):
        lib = os.path.normpath(os.path.join(here, up))
        for name in sorted(os.listdir(lib)) if os.path.isdir(lib) else ():
            if name.startswith("libsabodem.so."):
                return os.path.join(lib, name)
    found = ctypes.util.find_library("sabodem")
    if not found:
        raise OSError("libsabodem.so not found: set SABODEM_LIBRARY to its path")
    return found


library_path = _find_library()
_lib = ctypes.CDLL(library_path)


class _Vec3(ctypes.Structure):
    _fields_ = [("x", ctypes.c_double), ("y", ctypes.c_double), ("z", ctypes.c_double)]


class _BodyView(ctypes.Structure):
    """sd_body_view (sabodem.h): the body store's arrays, in store order."""
    _fields_ = [("n", ctypes.c_int),
                ("gid", ctypes.POINTER(ctypes.c_int32)), ("tag", ctypes.POINTER(ctypes.c_int32)),
                ("shape", ctypes.POINTER(ctypes.c_uint8)), ("fixed", ctypes.POINTER(ctypes.c_uint8)),
                ("pos", ctypes.POINTER(_Vec3)), ("vel", ctypes.POINTER(_Vec3)),
                ("omega", ctypes.POINTER(_Vec3)), ("axis", ctypes.POINTER(_Vec3)),
                ("force", ctypes.POINTER(_Vec3)), ("torque", ctypes.POINTER(_Vec3)),
                ("radius", ctypes.POINTER(ctypes.c_double)), ("half_length", ctypes.POINTER(ctypes.c_double)),
                ("bound_radius", ctypes.POINTER(ctypes.c_double)), ("mass", ctypes.POINTER(ctypes.c_double))]


_p = ctypes.c_void_p
_str_array = ctypes.POINTER(ctypes.c_char_p)
for name, res, args in [
        ("sd_version", ctypes.c_char_p, []),
        ("sd_scenario_load_file", ctypes.c_int, [ctypes.c_char_p, _str_array, ctypes.c_int, ctypes.POINTER(_p),
                                                 ctypes.c_char_p, ctypes.c_size_t]),
        ("sd_scenario_load_text", ctypes.c_int, [ctypes.c_char_p, ctypes.c_char_p, _str_array, ctypes.c_int,
                                                 ctypes.POINTER(_p), ctypes.c_char_p, ctypes.c_size_t]),
        ("sd_scenario_destroy", None, [_p]),
        ("sd_run_create", ctypes.c_int, [_p, ctypes.c_char_p, ctypes.c_int, ctypes.POINTER(_p), ctypes.c_char_p,
                                         ctypes.c_size_t]),
        ("sd_run_advance", ctypes.c_int, [_p, ctypes.c_double]),
        ("sd_run_advance_phase", ctypes.c_int, [_p]),
        ("sd_run_phase", ctypes.c_char_p, [_p]),
        ("sd_run_world", _p, [_p]),
        ("sd_run_finish", ctypes.c_int, [_p]),
        ("sd_run_status", ctypes.c_int, [_p, ctypes.POINTER(ctypes.c_char_p)]),
        ("sd_run_messages", ctypes.c_char_p, [_p]),
        ("sd_run_summary_json", _p, [_p]),
        ("sd_run_destroy", None, [_p]),
        ("sd_free", None, [_p]),
        ("sd_world_bodies", _BodyView, [_p]),
        ("sd_world_time", ctypes.c_double, [_p]),
        ("sd_world_step_count", ctypes.c_long, [_p])]:
    f = getattr(_lib, name)
    f.restype, f.argtypes = res, args


def version():
    """The library's version, "MAJOR.MINOR.PATCH"."""
    return _lib.sd_version().decode()


def _overrides(set):
    """{key: value} -> "key=value" strings (values as YAML: lists and vectors as JSON lists)"""
    items = [f"{k}={json.dumps(v) if not isinstance(v, str) else v}" for k, v in (set or {}).items()]
    return (ctypes.c_char_p * max(len(items), 1))(*[i.encode() for i in items]), len(items)


class Scenario:
    """A scenario: from a YAML file, YAML text or a dict of sections ({"flume": {"x_dam": 1.0}}),
    with overrides set={key: value} as `--set` gives them. Bad input raises ScenarioError."""

    def __init__(self, handle, name):
        self._h, self.name = handle, name

    @classmethod
    def _load(cls, fn, name, *args, set=None):
        arr, n = _overrides(set)
        h, err = _p(), ctypes.create_string_buffer(16384)
        if fn(*args, arr, n, ctypes.byref(h), err, len(err)):
            raise ScenarioError(err.value.decode().strip())
        return cls(h, name)

    @classmethod
    def from_file(cls, path, set=None):
        return cls._load(_lib.sd_scenario_load_file, str(path), str(path).encode(), set=set)

    @classmethod
    def from_text(cls, yaml, name="<text>", set=None):
        return cls._load(_lib.sd_scenario_load_text, name, yaml.encode(), name.encode(), set=set)

    @classmethod
    def from_dict(cls, sections, name="<dict>", set=None):
        # JSON is YAML: the dict goes in as flow-style YAML, each error at its line and column
        return cls.from_text(json.dumps(sections, indent=1), name=name, set=set)

    def __del__(self):
        if getattr(self, "_h", None):
            _lib.sd_scenario_destroy(self._h)
            self._h = None


class Run:
    """A run of a scenario writing its outputs into outdir: advance(t), advance_phase(), run(),
    bodies(), summary(). Use it in a `with` block, or call close()."""

    def __init__(self, scenario, outdir, threads=0):
        self.scenario, self.outdir = scenario, str(outdir)
        h, err = _p(), ctypes.create_string_buffer(16384)
        if _lib.sd_run_create(scenario._h, self.outdir.encode(), int(threads), ctypes.byref(h), err, len(err)):
            raise RunError(err.value.decode().strip())
        self._h = h

    def _check(self, going):
        msg = ctypes.c_char_p()
        if _lib.sd_run_status(self._h, ctypes.byref(msg)) not in (0, 130):
            raise RunError(f"{msg.value.decode()}: {_lib.sd_run_messages(self._h).decode().strip()}")
        return bool(going)

    def advance(self, t):
        """Step to the simulated time t (s) or the run's end; True while the run goes on."""
        return self._check(_lib.sd_run_advance(self._h, float(t)))

    def advance_phase(self):
        """Step to the end of the current phase; True while the run goes on."""
        return self._check(_lib.sd_run_advance_phase(self._h))

    def run(self):
        """Step to the end, write the final outputs; the summary as a dict."""
        self.advance(float("inf"))
        return self.finish()

    def finish(self):
        """End the run where it is (the final outputs and summary.json); the summary as a dict."""
        _lib.sd_run_finish(self._h)
        self._check(True)
        return self.summary()

    @property
    def phase(self):
        return _lib.sd_run_phase(self._h).decode()

    @property
    def time(self):
        return _lib.sd_world_time(_lib.sd_run_world(self._h))

    @property
    def steps(self):
        return _lib.sd_world_step_count(_lib.sd_run_world(self._h))

    def summary(self):
        """The summary (as summary.json has it) of the run as it stands, as a dict."""
        p = _lib.sd_run_summary_json(self._h)
        if not p:
            raise MemoryError("sd_run_summary_json")
        try:
            return json.loads(ctypes.string_at(p).decode())
        finally:
            _lib.sd_free(p)

    def bodies(self):
        """The bodies now, copied into numpy arrays (store order): gid, tag, shape (0 sphere,
        1 cylinder), fixed, pos, vel, omega, axis, force, torque (n x 3), radius, half_length,
        mass (n)."""
        v = _lib.sd_world_bodies(_lib.sd_run_world(self._h))
        n = v.n
        out = {}
        for name, _ in _BodyView._fields_[1:]:
            ptr = getattr(v, name)
            if n == 0:
                out[name] = np.zeros((0, 3) if ptr._type_ is _Vec3 else 0)
            elif ptr._type_ is _Vec3:
                out[name] = np.ctypeslib.as_array(ctypes.cast(ptr, ctypes.POINTER(ctypes.c_double)), (n, 3)).copy()
            else:
                out[name] = np.ctypeslib.as_array(ptr, (n,)).copy()
        return out

    def close(self):
        if getattr(self, "_h", None):
            _lib.sd_run_destroy(self._h)
            self._h = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()
