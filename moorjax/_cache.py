"""JAX's persistent compilation cache, on by default for moorjax.

Compiling a simulation (diffrax's step, the band Newton solver, the statics)
takes seconds; the compiled executables are kept on disk so that a new process
running the same *structure* again (same deck layout, segment counts, solver)
loads them instead of compiling. Values (EA, lengths, motions) are not part of
the key, so changing them reuses the cache.

Where: ``$MOORJAX_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/moorjax``, else
``~/.cache/moorjax`` (a ``jax`` subfolder). A cache directory the user already
gave JAX (``JAX_COMPILATION_CACHE_DIR`` or ``jax.config``) is left as it is.
Switch off with ``MOORJAX_COMPILATION_CACHE=0`` (also ``false``/``off``/``no``).
The folder may be deleted at any time; JAX refills it.
"""

from __future__ import annotations

import contextlib
import functools
import os
import weakref

_OFF = ("0", "false", "off", "no")


def cache_dir() -> str:
    """The folder moorjax keeps compiled executables in [path]."""
    root = os.environ.get("MOORJAX_CACHE_DIR")
    if not root:
        xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(xdg, "moorjax")
    return os.path.join(root, "jax")


def _switched_on(name: str) -> bool:
    """Whether the environment switch ``name`` is on (default on; off: :data:`_OFF`)."""
    return os.environ.get(name, "1").strip().lower() not in _OFF


def enabled() -> bool:
    """Whether the persistent cache is wanted (``MOORJAX_COMPILATION_CACHE``)."""
    return _switched_on("MOORJAX_COMPILATION_CACHE")


def enable_compilation_cache(jax) -> str | None:
    """Point JAX's persistent compilation cache at :func:`cache_dir` (unless
    switched off or already configured); returns the folder in use, or None."""
    if not enabled():
        return None
    current = jax.config.jax_compilation_cache_dir
    if current:
        return current
    path = cache_dir()
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:  # read-only home, no permission: run without the cache
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    # moorjax compiles many small functions (statics, outputs) besides the big
    # integration: keep them all, not only those over JAX's default 1 s
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path


# -- runtime checks without host callbacks -----------------------------------
#
# JAX never writes an executable that contains a host callback to the persistent
# cache. equinox compiles each ``eqx.error_if`` whose predicate is only known at
# run time into a host callback that raises; diffrax's ``diffeqsolve`` places
# three of them on its inputs (``(t1 - t0)·dt0 >= 0``, ``saveat.ts`` increasing
# and within [t0, t1]). moorjax checks exactly these on the host before it
# integrates (``dynamics.settings.plan`` raises ``ValueError`` naming the
# setting), so inside its integration they can never fire. equinox's documented
# switch for what an unresolved check compiles to is ``EQX_ON_ERROR``
# (``raise``/``nan``/``off``, read once at import into ``equinox._errors``);
# :func:`host_checked_inputs` selects ``nan`` (a failed check fills the checked
# value with NaN, no callback) while moorjax traces its integration only, and
# restores the user's choice afterwards. ``tests/test_speed_cache.py`` pins
# that a run is then served from the persistent cache in a new process.

def _equinox_errors():
    try:
        from equinox import _errors
    except ImportError:  # pragma: no cover - a future equinox layout
        return None
    return _errors if isinstance(getattr(_errors, "EQX_ON_ERROR", None), str) else None


@contextlib.contextmanager
def host_checked_inputs():
    """While tracing inside this context, equinox runtime checks compile without
    host callbacks (``EQX_ON_ERROR=nan`` semantics), so the compiled program can
    be kept in JAX's persistent cache. Use it only around code whose checked
    inputs were validated on the host; a user who set ``EQX_ON_ERROR=breakpoint``
    (debugging) keeps it. Nothing changes when equinox's layout differs."""
    errors = _equinox_errors()
    if errors is None or errors.EQX_ON_ERROR != "raise":
        yield
        return
    errors.EQX_ON_ERROR = "nan"
    try:
        yield
    finally:
        errors.EQX_ON_ERROR = "raise"


# -- whole programs stored by structure --------------------------------------
#
# JAX's persistent cache saves the XLA compile, but a new process still traces
# the Python program to a jaxpr and lowers it to find the cache key: seconds
# for a diffrax integration. :class:`StoredProgram` stores the lowered program
# itself (``jax.export``, StableHLO) under a key made of the inputs' *structure*
# (pytree layout with its static fields, shapes and dtypes), the moorjax source
# and the versions of JAX and its libraries; a new process with the same
# structure loads it (no tracing) and JAX's cache then serves the compile.


def programs_dir() -> str:
    """The folder moorjax keeps exported programs in [path] (beside :func:`cache_dir`)."""
    return os.path.join(os.path.dirname(cache_dir()), "programs")


_SOURCE = []


def _source_hash() -> str:
    """Hash of moorjax's own source files (a changed moorjax never loads an old program)."""
    if not _SOURCE:
        import hashlib

        h = hashlib.sha256()
        root = os.path.dirname(os.path.abspath(__file__))
        for folder, dirs, files in sorted(os.walk(root)):
            dirs.sort()
            for name in sorted(files):
                if name.endswith(".py"):
                    path = os.path.join(folder, name)
                    h.update(os.path.relpath(path, root).encode())
                    with open(path, "rb") as f:
                        h.update(f.read())
        _SOURCE.append(h.hexdigest())
    return _SOURCE[0]


@functools.cache
def _versions() -> str:
    """The versions of the packages behind a stored program, read once per
    process (``importlib.metadata`` scans the installed distributions: about
    12 ms a call, which every run paid before its first step)."""
    from importlib import metadata

    out = []
    for dist in ("jax", "jaxlib", "diffrax", "equinox", "optimistix", "lineax"):
        try:
            out.append(f"{dist}={metadata.version(dist)}")
        except metadata.PackageNotFoundError:
            out.append(f"{dist}=?")
    return ";".join(out)


#: packages whose code may be behind a stored program: moorjax's own source is
#: hashed into the key and the others' versions are; a class from anywhere else
#: (a user's own motion or load, defined in a script that may change between
#: processes) makes the structure unstorable, so it is always traced afresh
TRUSTED = ("moorjax", "diffrax", "equinox", "optimistix", "lineax", "jax", "jaxlib",
           "numpy", "builtins")


def _trusted(kind) -> bool:
    return kind.__module__.split(".")[0] in TRUSTED


def _describe(treedef, out: list) -> bool:
    """Append a text of every node of ``treedef`` (qualified class, static data);
    False when some static datum has no stable text (an object address) or a
    node's class is not from :data:`TRUSTED` packages."""
    if treedef.num_nodes == 1 and treedef.num_leaves == 1:
        out.append("*")
        return True
    node = treedef.node_data()
    if node is None:
        out.append("*" if treedef.num_leaves else "None")
        return True
    kind, aux = node
    text = f"{kind.__module__}.{kind.__qualname__}[{aux!r}]("
    if " at 0x" in text or not _trusted(kind):
        return False
    out.append(text)
    for child in treedef.children():
        if not _describe(child, out):
            return False
    out.append(")")
    return True


def _text_of(treedef):
    """:func:`_describe` of one tree structure as a tuple (``None``: no stable text)."""
    out = []
    return tuple(out) if _describe(treedef, out) else None


_cached_text_of = functools.lru_cache(maxsize=256)(_text_of)


def _described(treedef):
    """:func:`_text_of`, kept per structure: a run's arguments have hundreds of
    nodes, and every call of a stored program computes its key. A structure
    whose static data is not hashable is described afresh."""
    try:
        return _cached_text_of(treedef)
    except TypeError:
        return _text_of(treedef)


def _can_serialise() -> bool:
    """``jax.export`` serialises with the ``flatbuffers`` package."""
    import importlib.util

    return importlib.util.find_spec("flatbuffers") is not None


class StoredProgram:
    """``eqx.filter_jit(fn)`` whose lowered program is also stored on disk by the
    structure of its arguments (see above), so that a new process running the
    same structure neither traces nor lowers ``fn``.

    Falls back to the plain ``filter_jit`` when the cache is off, for traced
    arguments (under the caller's ``jit``/``grad``/``vmap``), when ``storable``
    says no (e.g. a program with host callbacks, which ``jax.export`` cannot
    store), or when the structure has no stable text.
    """

    def __init__(self, fn, storable=None, sharded=False, compile_for=None):
        self.fn = fn
        self.storable = storable
        #: what XLA compiles the program for (:func:`moorjax._xla_flags.compiler_options`):
        #: ``"runs"`` (a time integration, run many times), ``"members"`` (the
        #: same, vmapped over an ensemble's members), ``"once"`` (a static
        #: solve, run once per structure: compiled faster, runs slower) or ``None``
        #: (XLA's defaults). Only a call outside any trace takes them: under a
        #: caller's ``jit``/``grad``/``vmap`` the caller's program is what compiles.
        self.compile_for = compile_for
        self._jitted = {}  # options' text → eqx.filter_jit(fn, compiler_options=...)
        #: arguments may be sharded over several devices (an ensemble's members):
        #: each leaf's sharding is then part of the key and of the stored program
        self.sharded = sharded
        self._programs = {}
        self._ahead = {}  # key → Future of a compiled program (compile_ahead)
        self._keys = {}  # argument structure → key (see key)
        _INSTANCES.add(self)

    def compiler_options(self) -> dict | None:
        """The XLA options of a call made now (``None``: XLA's defaults and
        ``XLA_FLAGS``): this program's ``compile_for`` preset at the top level,
        ``None`` inside a trace (a nested ``jit`` takes no options)."""
        if self.compile_for is None or _top_level() is not True:
            return None
        from ._xla_flags import compiler_options

        return compiler_options(self.compile_for)

    @property
    def jitted(self):
        """``eqx.filter_jit(fn)``, with this program's compiler options where a
        call made now takes them."""
        options = self.compiler_options()
        text = repr(sorted(options.items())) if options else ""
        if text not in self._jitted:
            import equinox as eqx

            self._jitted[text] = eqx.filter_jit(self.fn, compiler_options=options)
        return self._jitted[text]

    def key(self, treedef, dynamic, static_leaves, leaves):
        """The stored program's key (``None``: not storable) of arguments whose
        tree is ``treedef``, whose leaves are dynamic where ``dynamic`` says
        (``leaves``, arrays or specs) and static elsewhere (``static_leaves``).
        Kept per structure: every call of a stored program computes it, and
        describing a run's arguments (hundreds of nodes) and hashing the text
        cost about 0.4 ms (case B integrates 20 s in about 11 ms)."""
        # dtype objects, not their text: str(dtype) was half of this key's 0.1 ms
        avals = tuple((x.shape, x.dtype, bool(getattr(x, "weak_type", False))) for x in leaves)
        if self.sharded:
            layouts = tuple(_layout(x) for x in leaves)
            if None in layouts:
                return None
            avals = tuple(a + (lay,) for a, lay in zip(avals, layouts))
        try:
            # the static leaves' types too: 1, 1.0 and True are equal but not alike
            memo = (treedef, dynamic, tuple((type(x), x) for x in static_leaves), avals)
            return self._keys[memo]
        except KeyError:
            pass
        except TypeError:  # an unhashable static leaf: not kept
            return self._key_text(treedef, dynamic, static_leaves, avals)
        key = self._keys[memo] = self._key_text(treedef, dynamic, static_leaves, avals)
        return key

    def _key_text(self, treedef, dynamic, static_leaves, avals):
        import hashlib

        import jax

        texts = [repr(x) for x in static_leaves]
        if any(" at 0x" in t for t in texts) or not all(
                _trusted(type(x)) for x in static_leaves) or not _trusted(self.fn):
            return None
        tree = _described(treedef)
        if tree is None:
            return None
        text = "\n".join([f"{self.fn.__module__}.{self.fn.__qualname__}", _source_hash(),
                          _versions(), jax.default_backend(), str(jax.config.jax_enable_x64),
                          *tree, "".join("d" if d else "s" for d in dynamic), *texts,
                          *(f"{shape}{dtype}{int(weak)}{''.join(rest)}"
                            for shape, dtype, weak, *rest in avals)])
        return hashlib.sha256(text.encode()).hexdigest()[:40]

    def _program(self, args, kwargs):
        """(key, program, leaves) for these arguments (arrays or
        ``jax.ShapeDtypeStruct``), loading or exporting the program; ``None``
        where the plain ``filter_jit`` must serve them (see the class)."""
        import jax

        folder = programs_dir() if enabled() and _can_serialise() else None
        if folder is None or (self.storable is not None and not self.storable(*args, **kwargs)):
            return None
        if self.compile_for is not None and _top_level() is False:
            return None  # inlined into the caller's program, which compiles it
        every, treedef = jax.tree_util.tree_flatten((args, kwargs))
        dynamic = tuple(_array_or_spec(x) for x in every)
        leaves = [x for x, d in zip(every, dynamic) if d]
        if any(isinstance(x, jax.core.Tracer) for x in leaves):
            return None
        static_leaves = [x for x, d in zip(every, dynamic) if not d]
        key = self.key(treedef, dynamic, static_leaves, leaves)
        if key is None:
            return None
        program = self._programs.get(key) or self._load(folder, key)
        if program is None:
            program = self._export(folder, key, treedef, dynamic, static_leaves, leaves)
        if program is _UNSTORABLE:
            return None
        return key, program, leaves

    def compile_ahead(self, *args, **kwargs) -> bool:
        """Prepare the call with arguments of this structure (arrays or
        ``jax.ShapeDtypeStruct`` for those not known yet) now: trace or load the
        program here, and compile it on a background thread, so that other work
        (the static equilibrium a run starts from, compiled and run meanwhile)
        overlaps the compile; the next call of this structure waits for it.
        XLA releases Python's lock while it compiles, so on a machine with two
        or more cores the two compiles run side by side (and the peak memory is
        both compiles'). False (nothing started) where the call would not use a
        stored program, or with ``MOORJAX_COMPILE_AHEAD=0`` (also
        ``false``/``off``/``no``)."""
        import concurrent.futures

        if not _switched_on("MOORJAX_COMPILE_AHEAD"):
            return False
        found = self._program(args, kwargs)
        if found is None:
            return False
        key, (call, out_tree, out_static), leaves = found
        if key in self._ahead or not hasattr(call, "lower"):
            return key in self._ahead
        specs = _specs(leaves, self.sharded)
        lowered = call.lower(*specs)  # here: lowering traces, and tracing holds the lock
        pool = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="moorjax-compile")
        self._ahead[key] = future = pool.submit(lowered.compile)
        _IN_FLIGHT.add(future)
        future.add_done_callback(_IN_FLIGHT.discard)
        pool.shutdown(wait=False)
        return True

    def __call__(self, *args, **kwargs):
        try:
            found = self._program(args, kwargs)
            if found is None:
                return self.jitted(*args, **kwargs)
            return self._run(found)
        except Exception as exc:  # a jaxlib that does not know an option: drop the options
            from ._xla_flags import reject_options

            if self.compile_for is None or not reject_options(exc):
                raise
            clear_programs()  # those compiled with the options
            return self(*args, **kwargs)

    def _run(self, found):
        import equinox as eqx
        import jax

        key, (call, out_tree, out_static), leaves = found
        ahead = self._ahead.pop(key, None)
        self._ahead.clear()  # prepared for calls that did not come: let them go
        if ahead is not None:
            try:
                call = ahead.result()
            except Exception:  # the compile failed off the main thread: compile here instead
                pass
            else:
                self._programs[key] = (call, out_tree, out_static)
        out = jax.tree_util.tree_unflatten(out_tree, call(*leaves))
        # outputs that are all arrays need no combine (a tree walk of ~15 µs)
        return out if out_static is None else eqx.combine(out, out_static)

    def _load(self, folder, key):
        import pickle

        import jax

        path = os.path.join(folder, key)
        if os.path.exists(path + ".none"):  # tried before: jax.export cannot store it
            self._programs[key] = _UNSTORABLE
            return _UNSTORABLE
        try:
            with open(path + ".hlo", "rb") as f:
                exported = jax.export.deserialize(bytearray(f.read()))
            with open(path + ".tree", "rb") as f:
                template, out_static = pickle.load(f)
            out_tree = jax.tree_util.tree_structure(template)
        except Exception:  # absent, partly written or from another layout: export anew
            return None
        program = (jax.jit(exported.call, compiler_options=self.compiler_options()), out_tree,
                   _static_part(out_static))
        self._programs[key] = program
        return program

    def _export(self, folder, key, treedef, dynamic, static_leaves, leaves):
        import pickle

        import equinox as eqx
        import jax

        found = {}

        def flat(*traced):
            given, fixed = iter(traced), iter(static_leaves)
            every = [next(given) if d else next(fixed) for d in dynamic]
            args, kwargs = jax.tree_util.tree_unflatten(treedef, every)
            out_dyn, out_static = eqx.partition(self.fn(*args, **kwargs), eqx.is_array)
            out_leaves, found["tree"] = jax.tree_util.tree_flatten(out_dyn)
            # the outputs' layout is stored as a template (0 for each array):
            # a pickled PyTreeDef of equinox modules does not load back
            found["template"] = jax.tree_util.tree_map(lambda _: 0, out_dyn)
            found["static"] = out_static
            return out_leaves

        specs = _specs(leaves, self.sharded)
        try:
            exported = jax.export.export(jax.jit(flat))(*specs)
            blob = exported.serialize()
        except Exception as exc:  # e.g. host callbacks: not storable
            if os.environ.get("MOORJAX_DEBUG_PROGRAMS"):
                raise
            del exc
            self._programs[key] = _UNSTORABLE
            _write(folder, key + ".none", b"")
            return _UNSTORABLE
        program = (jax.jit(exported.call, compiler_options=self.compiler_options()), found["tree"],
                   _static_part(found["static"]))
        self._programs[key] = program
        try:
            meta = pickle.dumps((found["template"], found["static"]))
        except Exception:  # unpicklable static outputs: keep it in memory only
            return program
        _write(folder, key + ".tree", meta)
        _write(folder, key + ".hlo", blob)  # last: a .hlo is always complete
        return program


#: every StoredProgram, for :func:`clear_programs`
_INSTANCES = weakref.WeakSet()

#: compiles started by ``compile_ahead`` that have not finished (used or not)
_IN_FLIGHT = set()


def _top_level() -> bool | None:
    """Whether no JAX trace (``jit``, ``grad``, ``vmap``) is running; ``None``
    where this JAX does not say (its private ``trace_ctx``): options are then
    never passed."""
    try:
        from jax._src import core

        return bool(core.trace_ctx.is_top_level())
    except Exception:  # pragma: no cover - another JAX layout
        return None


def compiling() -> bool:
    """Whether a compile started ahead is still running on its thread (its
    executable goes to JAX's persistent cache when it ends)."""
    return any(not f.done() for f in list(_IN_FLIGHT))


def clear_programs():
    """Forget the programs every :class:`StoredProgram` holds in memory (the
    files stay): with ``jax.clear_caches()`` this frees the compiled
    executables of a long session (``compile_ahead`` keeps its compiled
    program itself, which JAX's cache clearing does not reach)."""
    for program in list(_INSTANCES):
        program._programs.clear()
        program._ahead.clear()
        program._jitted.clear()


def _specs(leaves, sharded=False) -> list:
    """The shape, dtype and weak type of each leaf (array or spec); with ``sharded``
    also its sharding where it spans several devices."""
    import jax

    return [jax.ShapeDtypeStruct(x.shape, x.dtype, weak_type=bool(getattr(x, "weak_type", False)),
                                 sharding=x.sharding if sharded and _layout(x) else None)
            for x in leaves]


def _layout(x) -> str | None:
    """How a leaf is laid out over devices, as key text: ``""`` on one device,
    the mesh and partition spec of a ``NamedSharding`` over several, ``None``
    (not storable) for another sharding over several."""
    sharding = getattr(x, "sharding", None)
    if sharding is None or len(sharding.device_set) <= 1:
        return ""
    mesh, spec = getattr(sharding, "mesh", None), getattr(sharding, "spec", None)
    if mesh is None or spec is None:
        return None
    return f"@{dict(mesh.shape)}{tuple(spec)}"


def _static_part(tree):
    """A program's static outputs as stored beside it: ``None`` where they hold
    nothing but ``None`` (decided once, so that a call skips ``eqx.combine``)."""
    import jax

    return tree if jax.tree_util.tree_leaves(tree) else None


def _array_or_spec(x) -> bool:
    import equinox as eqx
    import jax

    return eqx.is_array(x) or isinstance(x, jax.ShapeDtypeStruct)


#: marks a structure whose program jax.export cannot store (host callbacks)
_UNSTORABLE = object()


def _write(folder, name, data: bytes):
    """Write a file atomically (a concurrent reader sees all of it or nothing);
    a read-only or full disk only costs the stored copy."""
    try:
        os.makedirs(folder, exist_ok=True)
        tmp = os.path.join(folder, f"{name}.{os.getpid()}.tmp")
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, os.path.join(folder, name))
    except OSError:
        pass
