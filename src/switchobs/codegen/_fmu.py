"""The generated observer as an FMI 3.0 or 2.0 co-simulation FMU (a zip: model description, sources, binary).

The wrapper (``_fmu_wrapper.c``, rendered per observer) keeps one instance
struct: the held signals, the parameter array the C API takes (the model values
and ``K_plus_<state>`` / ``K_minus_<state>``, tunable), the initial state
``xhat0_<state>`` (fixed parameters, the start values), the state, the
original-coordinate estimate and the status of the last step.  One ``doStep``
of any length ``h`` is one call of ``<prefix>_step(xhat, signals, params, h)``
with the inputs held (sub-stepping inside ``_step`` where the observer has
``H_MAX``).  A refused step leaves the state unchanged, sets ``status`` to the
code and returns ``Discard`` with a log message naming the status
(``<prefix>_status_message``).  The instance is the FMU's only allocation: the
environment's ``allocateMemory`` in FMI 2.0; ``calloc`` in FMI 3.0, which
passes no allocator; no global mutable state, so instances are independent.

The binary is built with the system C compiler against the FMI headers FMPy
ships (``fmpy/c-code``; the importing tool has its own copy), without
``-march=native`` (the FMU runs on other machines of the same platform) and
with ``-ffp-contract=off``, so its steps equal those of the host build.

Value references: 0 ``time`` (FMI 3.0 only), then the signals, the parameters,
the initial state, the state, the original coordinates, ``status``.
"""

from __future__ import annotations

import hashlib
import io
import os
import platform
import re
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path
from string import Template
from xml.sax.saxutils import escape, quoteattr

from .. import __version__
from ..exceptions import CodegenError, PrerequisiteError
from ._build import BUILD_FLAGS, compile_sources
from ._emit import float_literal
from ._observer import GeneratedObserver

__all__ = ["FMI_VERSIONS", "FMUVariable", "GeneratedFMU", "build_fmu", "fmi3_common", "fmi_headers", "fmu_token",
           "generate_fmu"]

#: The FMI versions of :func:`generate_fmu`.
FMI_VERSIONS = (2, 3)

_TEMPLATE = Path(__file__).with_name("_fmu_wrapper.c")
_FMI3_COMMON = Path(__file__).with_name("_fmi3_common.c")
#: Portable build (no -march=native), no contraction into FMAs: the host build's arithmetic.
_FLAGS = (*BUILD_FLAGS, "-ffp-contract=off")


def fmi_headers(version: int) -> dict[str, str]:
    """The FMI ``version`` headers (name -> text) of the installed FMPy (``fmpy/c-code``).

    Raises
    ------
    PrerequisiteError
        If FMPy is not installed (``pip install switchobs[fmu]``).
    """
    try:
        import fmpy
    except ImportError:
        raise PrerequisiteError("building an FMU needs the FMI headers that FMPy ships; install it with "
                                "pip install 'switchobs[fmu]' (or pip install fmpy)") from None
    root = Path(fmpy.__file__).parent / "c-code"
    names = [f"fmi{version}Functions.h", f"fmi{version}FunctionTypes.h",
             f"fmi{version}{'PlatformTypes' if version == 3 else 'TypesPlatform'}.h"]
    try:
        return {name: (root / name).read_text(encoding="utf-8") for name in names}
    except OSError as exc:
        raise PrerequisiteError(f"the FMI {version} headers are missing from {str(root)!r} ({exc.strerror}); "
                                "reinstall fmpy") from None


_TYPEDEF = re.compile(r"typedef\s+fmi3Status\s+(fmi3\w+)TYPE\s*\((.*?)\);", re.S)


def fmi3_common(template: str) -> str:
    """The FMI 3.0 functions of a co-simulation wrapper ``template`` that every wrapper defines alike
    (``_fmi3_common.c``: the version, instantiation, event mode, termination, reset, step mode), then those neither
    defines (model exchange, scheduled execution, clocks, FMU state...), each returning ``fmi3Error`` with a log
    message through the wrapper's ``swobs_fail(SWOBS_INST, function, why)``.  FMI 3.0 importers (FMPy) load every
    function of ``fmi3Functions.h``, so all are defined; the signatures come from the standard's own header.
    Used by :func:`generate_fmu` and the quarter car's plant FMU (:func:`switchobs.plants.generate_plant_fmu`)."""
    common = _FMI3_COMMON.read_text(encoding="utf-8")
    return common + "\n" + _fmi3_stubs(template + common)


def _fmi3_stubs(template: str) -> str:
    """Definitions of the FMI 3.0 functions of ``fmi3FunctionTypes.h`` that ``template`` does not define."""
    types_header = fmi_headers(3)["fmi3FunctionTypes.h"]
    defined = set(re.findall(r"\b(fmi3\w+)\s*\(fmi3Instance instance", template)) | \
        set(re.findall(r"SWOBS_NONE\((fmi3\w+),", template))
    out = []
    for name, params in _TYPEDEF.findall(types_header):
        if name in defined:
            continue
        params = " ".join(params.split())
        names = [re.sub(r"\[\]$", "", p.strip()).split()[-1].lstrip("*") for p in params.split(",")]
        if names[0] != "instance":
            raise CodegenError(f"unexpected FMI 3.0 signature of {name}: ({params})")
        unused = " ".join(f"(void){n};" for n in names[1:])
        out += [f"fmi3Status {name}({params})",
                "{",
                *([f"    {unused}"] if unused else []),
                f'    return instance == NULL ? fmi3Error : swobs_fail(SWOBS_INST, "{name}", '
                '"not supported by this co-simulation FMU");',
                "}", ""]
    return "\n".join(out)


def _platform(version: int) -> str:
    """The binaries folder of this platform: FMI 3.0's ``<arch>-<os>`` tuple or FMI 2.0's ``linux64``..."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    system = {"linux": "linux", "darwin": "darwin", "win32": "windows"}.get(sys.platform)
    if system is None:
        raise CodegenError(f"no FMI platform name for {sys.platform!r}; build the FMU from its sources")
    if version == 3:
        return f"{arch}-{system}"
    bits = "64" if sys.maxsize > 2**32 else "32"
    return {"linux": "linux", "darwin": "darwin", "windows": "win"}[system] + bits


def _shared_suffix() -> str:
    return {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")


@dataclass(frozen=True)
class FMUVariable:
    """One variable of an FMU's model description (``kind`` "real": Float64 / Real, "int": Int32 / Integer)."""

    name: str
    vr: int
    kind: str          # "real" or "int"
    causality: str
    variability: str
    start: float | int | None = None
    initial: str | None = None
    description: str = ""


def _signal_start(gen: GeneratedObserver) -> list[float]:
    """The signals' start values: 1 or -1 for an external signal of declared sign (s(y) often divides by it),
    else 0."""
    out = []
    for role in gen.signal_roles or ("",) * gen.ns:
        out.append(1.0 if "(> 0)" in role else -1.0 if "(< 0)" in role else 0.0)
    return out


def _variables(gen: GeneratedObserver, version: int, initial_state: tuple[float, ...]) -> list[FMUVariable]:
    out = [FMUVariable("time", 0, "real", "independent", "continuous", description="simulation time")] \
        if version == 3 else []
    vr = 1
    for name, role, start in zip(gen.signal_names, gen.signal_roles or ("",) * gen.ns, _signal_start(gen)):
        out.append(FMUVariable(name, vr, "real", "input", "continuous", start, description=role))
        vr += 1
    for name, value in zip(gen.param_names, gen.default_params):
        out.append(FMUVariable(name, vr, "real", "parameter", "tunable", value, "exact", "runtime parameter"))
        vr += 1
    for name, value in zip(gen.state_names, initial_state):
        out.append(FMUVariable(f"xhat0_{name}", vr, "real", "parameter", "fixed", value, "exact",
                             f"initial estimate of {name}"))
        vr += 1
    for name in gen.state_names:
        out.append(FMUVariable(f"xhat_{name}", vr, "real", "output", "discrete", initial="calculated",
                             description=f"estimate of {name} after the last step"))
        vr += 1
    for name in gen.original_names:
        out.append(FMUVariable(f"x_{name}", vr, "real", "output", "discrete", initial="calculated",
                             description=f"estimate of {name} in the original coordinates (phi^-1(xhat))"))
        vr += 1
    out.append(FMUVariable("status", vr, "int", "output", "discrete", initial="calculated",
                         description=f"status code of the last step ({gen.prefix}_status_message)"))
    names = [v.name for v in out]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise CodegenError(f"the FMU variable names {clash} occur twice (a signal or parameter named like an "
                           "output); rename them in the model")
    return out


def _number(value: float | int) -> str:
    return repr(int(value)) if isinstance(value, int) else repr(float(value))


#: The log categories of the observer FMUs (name, description).
_OBSERVER_LOG = (("logStatusWarning", "the original coordinates were refused"),
                 ("logStatusDiscard", "a step refused: its status"),
                 ("logStatusError", "a call the FMU cannot serve"))


def _model_description(identifier: str, text: str, version: int, token: str, variables: list[FMUVariable],
                       sources: tuple[str, ...], dt: float, log: tuple[tuple[str, str], ...]) -> str:
    description = quoteattr(text)
    head = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription fmiVersion="{version}.0" modelName={quoteattr(identifier)} '
        f'{"instantiationToken" if version == 3 else "guid"}="{token}" description={description} '
        f'generationTool="switchobs {__version__}" variableNamingConvention="flat"'
        + (' numberOfEventIndicators="0"' if version == 2 else '') + '>',
    ]
    if version == 3:
        head.append(f'  <CoSimulation modelIdentifier={quoteattr(identifier)} '
                    'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="false" '
                    'canSerializeFMUState="false" hasEventMode="false"/>')
    else:
        head += [f'  <CoSimulation modelIdentifier={quoteattr(identifier)} '
                 'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="false" '
                 'canSerializeFMUstate="false">',
                 '    <SourceFiles>', *[f'      <File name="{s}"/>' for s in sources], '    </SourceFiles>',
                 '  </CoSimulation>']
    head += ['  <LogCategories>',
             *[f'    <Category name="{name}" description={quoteattr(what)}/>' for name, what in log],
             '  </LogCategories>',
             f'  <DefaultExperiment startTime="0" stopTime="1" stepSize="{dt!r}"/>',
             '  <ModelVariables>']
    body = []
    for index, v in enumerate(variables, start=1):
        attrs = (f'name={quoteattr(v.name)} valueReference="{v.vr}" description={quoteattr(v.description)} '
                 f'causality="{v.causality}" variability="{v.variability}"'
                 + (f' initial="{v.initial}"' if v.initial else ''))
        start = "" if v.start is None else f' start="{_number(v.start)}"'
        if version == 3:
            tag = "Float64" if v.kind == "real" else "Int32"
            body.append(f'    <{tag} {attrs}{start}/>')
        else:
            tag = "Real" if v.kind == "real" else "Integer"
            body.append(f'    <ScalarVariable {attrs}><{tag}{start}/></ScalarVariable>  <!-- index {index} -->')
    outputs = [(i, v) for i, v in enumerate(variables, start=1) if v.causality == "output"]
    if version == 3:
        structure = [*[f'    <Output valueReference="{v.vr}"/>' for _, v in outputs],
                     *[f'    <InitialUnknown valueReference="{v.vr}"/>' for _, v in outputs]]
    else:
        structure = ['    <Outputs>', *[f'      <Unknown index="{i}"/>' for i, _ in outputs], '    </Outputs>',
                     '    <InitialUnknowns>', *[f'      <Unknown index="{i}"/>' for i, _ in outputs],
                     '    </InitialUnknowns>']
    return "\n".join([*head, *body, '  </ModelVariables>', '  <ModelStructure>', *structure,
                      '  </ModelStructure>', '</fmiModelDescription>', ''])


def _build_description(identifier: str, sources: tuple[str, ...]) -> str:
    return "\n".join([
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<fmiBuildDescription fmiVersion="3.0">',
        f'  <BuildConfiguration modelIdentifier={quoteattr(identifier)} '
        f'description={quoteattr("C99; link with the C math library (-lm)")}>',
        '    <SourceFileSet language="C99">',
        *[f'      <SourceFile name="{escape(s)}"/>' for s in sources],
        '    </SourceFileSet>',
        '  </BuildConfiguration>',
        '</fmiBuildDescription>', ''])


@dataclass(frozen=True)
class GeneratedFMU:
    """An FMU of a generated observer.

    Attributes
    ----------
    prefix : str
        The observer's C prefix: the FMU's model identifier and file stem.
    fmi_version : {2, 3}
    platform : str
        The binaries folder (``x86_64-linux``, ``linux64``).
    model_description : str
        ``modelDescription.xml``.
    wrapper : str
        ``sources/<prefix>_fmi<version>.c``.
    data : bytes
        The zip archive ``<prefix>.fmu``.
    value_references : mapping str -> int
        The value reference of every variable by name.
    """

    prefix: str
    fmi_version: int
    platform: str
    model_description: str
    wrapper: str
    data: bytes
    value_references: dict[str, int]

    @property
    def file_name(self) -> str:
        return f"{self.prefix}.fmu"

    def __str__(self) -> str:
        return (f"FMI {self.fmi_version}.0 co-simulation FMU {self.file_name} ({self.platform} binary, "
                f"{len(self.value_references)} variables, {len(self.data)} bytes)")

    def write(self, path: str | os.PathLike) -> Path:
        """Write the archive to ``path`` atomically (:func:`switchobs._atomic.atomic_file`)."""
        from .._atomic import atomic_file
        with atomic_file(path, what="the FMU") as partial:
            partial.write_bytes(self.data)
        return Path(path)


def generate_fmu(gen: GeneratedObserver, *, fmi_version: int = 3, initial_state: dict[str, float] | None = None,
                 step_size: float = 1e-3, compiler: str | None = None,
                 cache_dir: str | os.PathLike | None = None) -> GeneratedFMU:
    """The FMI ``fmi_version`` co-simulation FMU of a generated observer, with a binary for this platform.

    Parameters
    ----------
    gen : GeneratedObserver
        Any observer of :func:`~switchobs.codegen.generate_observer` (switched or adaptive, every method and
        real type) or :func:`~switchobs.codegen.generate_super_twisting`.
    fmi_version : {3, 2}
        FMI 3.0 (default) or FMI 2.0 co-simulation.
    initial_state : mapping state name -> float, optional
        Start values of ``xhat0_<state>`` (default 0).
    step_size : float
        The DefaultExperiment's step size (s); any step length works.
    compiler, cache_dir
        As :func:`~switchobs.codegen.compile_sources` (the binary is cached like the observers').

    Returns
    -------
    GeneratedFMU

    Raises
    ------
    CodegenError
        Unknown FMI version, unknown state name, a variable name clash, or a failed compilation.
    PrerequisiteError
        FMPy (the FMI headers) is not installed.

    References
    ----------
    FMI 3.0 and FMI 2.0.4 standards (Modelica Association), co-simulation interface.

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> from switchobs.design import design
    >>> from switchobs.codegen import generate_observer
    >>> m = builtin_model("abs-xbs3")
    >>> fmu = generate_fmu(generate_observer(m, design(m, "-40,-60,-60")), fmi_version=2)
    >>> fmu.file_name, fmu.value_references["status"]  # 0: time (FMI 3.0), 3 signals, 9 params, 2 x 3 states
    ('switchobs_abs_xbs3.fmu', 19)
    """
    if fmi_version not in FMI_VERSIONS:
        raise CodegenError(f"FMI version must be one of {list(FMI_VERSIONS)}, got {fmi_version!r}")
    initial_state = dict(initial_state or {})
    unknown = sorted(set(initial_state) - set(gen.state_names))
    if unknown:
        raise CodegenError(f"initial_state names {unknown}, which are not states of the observer "
                           f"({list(gen.state_names)})")
    x0 = tuple(float(initial_state.get(n, 0.0)) for n in gen.state_names)
    headers = fmi_headers(fmi_version)
    variables = _variables(gen, fmi_version, x0)
    P = gen.prefix.upper()
    template = _TEMPLATE.read_text(encoding="utf-8")
    # the token names this exact observer and interface: any change of the sources changes it
    token = fmu_token(gen.header, gen.source, str(fmi_version), repr(x0))
    wrapper = Template(template).substitute(fmi3_common=fmi3_common(template) if fmi_version == 3 else "",
        prefix=gen.prefix, P=P, version=fmi_version, no=len(gen.original_names), token=token,
        discard=f"fmi{fmi_version}Discard",
        allocation="fmi2CallbackFunctions.allocateMemory" if fmi_version == 2 else "calloc (FMI 3.0 passes no "
                                                                                  "allocator)",
        signal_start=", ".join(float_literal(v, "double") for v in _signal_start(gen)),
        x0_start=", ".join(float_literal(v, "double") for v in x0))
    return build_fmu(gen.prefix, f"{gen.kind} observer of model {gen.model_name!r}: {gen.description}",
                     variables, {**gen.files, **headers}, wrapper, fmi_version=fmi_version, token=token,
                     step_size=step_size, log=_OBSERVER_LOG, readme=gen.readme, compiler=compiler,
                     cache_dir=cache_dir)


def fmu_token(*texts: str) -> str:
    """The instantiation token (FMI 2.0 GUID) of an FMU made of ``texts``: any change of them changes it."""
    digest = hashlib.sha256("\0".join(texts).encode()).hexdigest()
    return "{" + "-".join([digest[:8], digest[8:12], digest[12:16], digest[16:20], digest[20:32]]) + "}"


def build_fmu(identifier: str, description: str, variables: list[FMUVariable], files: dict[str, str], wrapper: str,
              *, fmi_version: int, token: str, step_size: float, log: tuple[tuple[str, str], ...], readme: str,
              compiled: tuple[str, ...] | None = None, compiler: str | None = None,
              cache_dir: str | os.PathLike | None = None) -> GeneratedFMU:
    """The co-simulation FMU ``identifier`` of a rendered ``wrapper`` (``sources/<identifier>_fmi<v>.c``) over the
    C ``files`` (``<identifier>.c`` the model's source, the headers it includes), compiled for this platform.

    ``variables`` are the model description's, ``log`` its log categories (name, description), ``readme`` the
    archive's ``documentation/README.md``; ``compiled`` the translation units (default: ``<identifier>.c`` and the
    wrapper; a wrapper that includes the model's source compiles alone).  Shared by :func:`generate_fmu` and the quarter car's plant FMU
    (:func:`switchobs.plants.generate_plant_fmu`).

    Raises
    ------
    CodegenError
        A failed compilation, or no FMI platform name for this system.
    """
    wrapper_name = f"{identifier}_fmi{fmi_version}.c"
    sources = (f"{identifier}.c", wrapper_name) if compiled is None else (*compiled, wrapper_name)
    library = compile_sources({**files, wrapper_name: wrapper}, sources, f"{identifier}_fmi{fmi_version}",
                              compiler=compiler, flags=_FLAGS, cache_dir=cache_dir, host=False)
    plat = _platform(fmi_version)
    model_description = _model_description(identifier, description, fmi_version, token, variables, sources,
                                           step_size, log)
    archive = {"modelDescription.xml": model_description.encode(),
               **{f"sources/{name}": text.encode() for name, text in files.items()
                  if name.startswith(identifier) and name.endswith((".c", ".h"))},
               f"sources/{wrapper_name}": wrapper.encode(),
               "documentation/README.md": readme.encode(),
               f"binaries/{plat}/{identifier}{_shared_suffix()}": library.read_bytes()}
    if fmi_version == 3:
        archive["sources/buildDescription.xml"] = _build_description(identifier, sources).encode()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(archive):
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))  # reproducible archive
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = (0o755 if name.startswith("binaries/") else 0o644) << 16
            zf.writestr(info, archive[name])
    return GeneratedFMU(prefix=identifier, fmi_version=fmi_version, platform=plat,
                        model_description=model_description, wrapper=wrapper, data=buffer.getvalue(),
                        value_references={v.name: v.vr for v in variables})
