"""The ASAP2 (A2L) calibration description and the calibration object it addresses.

A program is linked from the generated C and ``<prefix>_calibration.c``; its symbol table (``nm``) gives the
addresses; pya2ldb (an A2L parser switchobs did not write) reads the file back, and every address equals the
ELF's.  Writing the calibration array through its symbol changes the step exactly as the parameter array does.
"""

from __future__ import annotations

import ctypes
import re
import shutil
import subprocess

import numpy as np
import pytest

from switchobs.cli.main import main
from switchobs.codegen import CObserver, generate_observer
from switchobs.codegen._a2l import a2l_symbols, calibration_files, elf_symbols, generate_a2l
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.model import builtin_model

MAIN = """#include "{p}_calibration.h"
int main(void)
{{
    {p}_real signals[{P}_NS] = {{ 1, 20, 0 }};
    return (int){p}_calibrated_step(signals, ({p}_real)0.001);
}}
"""


def _cc() -> str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler is installed: the calibration object and A2L addresses are NOT checked")
    if shutil.which("nm") is None:
        pytest.skip("nm is not installed: the A2L addresses are NOT checked against the ELF")
    return cc


def _build(gen, directory, *, shared: bool = False):
    """The program (or shared library) of the observer and its calibration object; its path."""
    cc = _cc()
    files = {**gen.files, **calibration_files(gen), "main.c": MAIN.format(p=gen.prefix, P=gen.prefix.upper())}
    for name, text in files.items():
        (directory / name).write_text(text)
    sources = [f"{gen.prefix}.c", f"{gen.prefix}_calibration.c"] + ([] if shared else ["main.c"])
    out = directory / ("libcal.so" if shared else "program")
    flags = ["-shared", "-fPIC"] if shared else []
    proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", *flags, "-o", str(out),
                           *sources, "-lm"], cwd=directory, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def xbs3():
    m = builtin_model("abs-xbs3")
    return generate_observer(m, design(m, "-40,-60,-60"))


@pytest.fixture(scope="module")
def program(xbs3, tmp_path_factory):
    return _build(xbs3, tmp_path_factory.mktemp("a2l"))


@pytest.mark.slow
def test_pya2l_parses_the_file_and_every_address_is_the_elfs(xbs3, program, tmp_path, capfd):
    pya2l = pytest.importorskip("pya2l", reason="pya2ldb is not installed: the A2L file is NOT parsed")
    from pya2l import model as a2l

    symbols = elf_symbols(program)
    path = tmp_path / "x.a2l"
    path.write_text(generate_a2l(xbs3, addresses=symbols), encoding="latin-1")
    capfd.readouterr()
    db = pya2l.import_a2l(str(path), in_memory=True, progress_bar=False, loglevel="ERROR")
    assert "[error]" not in "".join(capfd.readouterr())   # the parser's own complaints (it logs, not raises)
    params = symbols[f"{xbs3.prefix}_calibration"]
    chars = {c.name: c for c in db.query(a2l.Characteristic).all()}
    assert list(chars) == list(xbs3.param_names)         # one per model value and gain, in array order
    for i, name in enumerate(xbs3.param_names):
        c = chars[name]
        assert (c.type, c.address, c.deposit, c.conversion) == ("VALUE", params + 8 * i, "RL_FLOAT64_IEEE",
                                                                "CM_IDENTICAL")
        assert (c.symbol_link.symbolName, c.symbol_link.offset) == (f"{xbs3.prefix}_calibration", 8 * i)
    # declared signs as limits: a > 0, b < 0 (the step's BAD_PARAM checks)
    assert chars["a"].lowerLimit > 0 and chars["b"].upperLimit < 0 and chars["c"].lowerLimit < 0
    meas = {m.name: m for m in db.query(a2l.Measurement).all()}
    for i, name in enumerate(xbs3.state_names):
        assert (meas[f"xhat_{name}"].datatype, meas[f"xhat_{name}"].ecu_address.address) == \
            ("FLOAT64_IEEE", symbols[f"{xbs3.prefix}_xhat"] + 8 * i)
    assert (meas["status"].datatype, meas["status"].ecu_address.address) == ("SLONG",
                                                                             symbols[f"{xbs3.prefix}_status"])
    assert db.query(a2l.ModCommon).one().byte_order.byteOrder == "MSB_LAST"
    segment = db.query(a2l.MemorySegment).one()
    assert (segment.address, segment.size, segment.memoryType) == (params, 8 * xbs3.np, "RAM")


def test_calibration_array_written_through_its_symbol_retunes_the_step(xbs3, tmp_path):
    """What a calibration tool does over XCP: write an element of <prefix>_calibration; the next calibrated steps
    equal the C _run with that parameter, bit for bit, and the status is measured."""
    lib = ctypes.CDLL(str(_build(xbs3, tmp_path, shared=True)))
    real = ctypes.c_double
    cal = (real * xbs3.np).in_dll(lib, f"{xbs3.prefix}_calibration")
    xhat = (real * xbs3.nx).in_dll(lib, f"{xbs3.prefix}_xhat")
    status = ctypes.c_int32.in_dll(lib, f"{xbs3.prefix}_status")
    step = getattr(lib, f"{xbs3.prefix}_calibrated_step")
    step.argtypes, step.restype = [ctypes.POINTER(real), real], ctypes.c_int32
    assert list(cal) == list(xbs3.default_params)        # initialised with the designed values
    cal[xbs3.param_index("K_plus_z2")] = -50.0
    t = np.arange(200) * 1e-3
    rows = np.column_stack([30 * np.sin(40 * t), 25 - 3 * t, 500 * np.cos(40 * t)])
    xhat[:] = [0.1, 0.2, 0.3]
    got = []
    for row in rows:
        assert step((real * 3)(*row), 1e-3) == 0
        got.append(list(xhat))
    want = CObserver(xbs3, params={"K_plus_z2": -50.0}).run([0.1, 0.2, 0.3], rows, 1e-3)
    assert np.array_equal(got, want)
    assert step((real * 3)(1.0, -2.0, 0.0), 1e-3) != 0 and status.value == step((real * 3)(1.0, -2.0, 0.0), 1e-3)


def test_float_a2l_is_balanced_and_links_symbols_the_object_defines(tmp_path, capsys):
    """Without a parser: /begin and /end balance, FLOAT32_IEEE for the float build, every SYMBOL_LINK names a
    symbol of the object file (nm), and the CLI writes the files."""
    m = builtin_model("abs-xbs4")
    out = tmp_path / "c"
    assert main(["codegen", "abs-xbs4", "--spectrum=-40,-60,-60,-60", "--real", "float", "--a2l",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    gen = generate_observer(m, design(m, "-40,-60,-60,-60"), real="float")
    text = (out / f"{gen.prefix}.a2l").read_text()
    assert text == generate_a2l(gen)                     # no addresses: 0 and SYMBOL_LINKs
    stack = []
    for line in text.splitlines():
        if (begin := re.match(r"\s*/begin (\w+)", line)):
            stack.append(begin.group(1))
        elif (end := re.match(r"\s*/end (\w+)", line)):
            assert stack.pop() == end.group(1)
    assert stack == []
    assert text.count("/begin CHARACTERISTIC") == gen.np == text.count(" VALUE 0x0 RL_FLOAT32_IEEE ")
    cc = _cc()
    proc = subprocess.run([cc, "-std=c99", "-c", f"{gen.prefix}_calibration.c"], cwd=out, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    defined = elf_symbols(out / f"{gen.prefix}_calibration.o")
    linked = set(re.findall(r'SYMBOL_LINK "(\w+)"', text))
    assert linked == set(a2l_symbols(gen)) and linked <= set(defined)
    section = subprocess.run(["objdump", "-t", f"{gen.prefix}_calibration.o"], cwd=out, capture_output=True,
                             text=True).stdout if shutil.which("objdump") else ""
    if section:
        assert re.search(rf"\.{gen.prefix}_cal\s.*{gen.prefix}_calibration\b", section), section


def test_addresses_without_the_calibration_symbols_are_refused(xbs3):
    with pytest.raises(CodegenError, match=r"defines no symbol \['switchobs_abs_xbs3_calibration'"):
        generate_a2l(xbs3, addresses={"main": 0x1000})


def test_cortex_m4_build_addresses_are_in_the_a2l(xbs3, tmp_path):
    """A target build (arm-none-eabi-gcc, Cortex-M4, newlib): the calibration array lands in its own section,
    8-byte aligned, and the A2L made from arm-none-eabi-nm's symbol table addresses each element there."""
    cc, nm = shutil.which("arm-none-eabi-gcc"), shutil.which("arm-none-eabi-nm")
    if cc is None or nm is None:
        pytest.skip("arm-none-eabi-gcc is not installed: the target build's A2L addresses are NOT checked")
    files = {**xbs3.files, **calibration_files(xbs3), "main.c": MAIN.format(p=xbs3.prefix, P=xbs3.prefix.upper())}
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    elf = tmp_path / "observer.elf"
    proc = subprocess.run([cc, "-std=c99", "-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16",
                           "-O2", "-Wall", "-Wextra", "-Werror", "--specs=nosys.specs", "-o", str(elf), "main.c",
                           f"{xbs3.prefix}.c", f"{xbs3.prefix}_calibration.c", "-lm"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    symbols = elf_symbols(elf, nm=nm)
    base = symbols[f"{xbs3.prefix}_calibration"]
    assert base % 8 == 0
    text = generate_a2l(xbs3, addresses=symbols)
    found = re.findall(r"/begin CHARACTERISTIC (\w+) \"[^\"]*\" VALUE 0x([0-9A-F]+) ", text)
    assert found == [(name, f"{base + 8 * i:X}") for i, name in enumerate(xbs3.param_names)]
    ecu = re.findall(r"ECU_ADDRESS 0x([0-9A-F]+)", text)
    assert ecu == [f"{symbols[f'{xbs3.prefix}_xhat'] + 8 * i:X}" for i in range(xbs3.nx)] + \
        [f"{symbols[f'{xbs3.prefix}_status']:X}"]
    objdump = shutil.which("arm-none-eabi-objdump")
    if objdump:
        table = subprocess.run([objdump, "-t", str(elf)], capture_output=True, text=True).stdout
        assert re.search(rf"\.{xbs3.prefix}_cal\s+0*48\s+{xbs3.prefix}_calibration\b", table), table
