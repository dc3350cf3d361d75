"""The machine line beside every timing: CPU generations that a bare model name hides."""

from drake_mh.study.machine import _describe, cpu_model

ZEN5 = """processor\t: 0
vendor_id\t: AuthenticAMD
cpu family\t: 26
model\t\t: 2
model name\t: AMD EPYC
flags\t\t: fpu sse2 avx avx2 fma avx512f avx512dq

processor\t: 1
vendor_id\t: AuthenticAMD
cpu family\t: 25
model\t\t: 17
model name\t: Another CPU
flags\t\t: fpu sse2
"""

SKYLAKE = """processor\t: 0
cpu family\t: 6
model\t\t: 85
model name\t: Intel(R) Xeon(R) Gold 6148 CPU @ 2.40GHz
flags\t\t: fpu sse2 avx avx2 fma
"""

ARM = """processor\t: 0
BogoMIPS\t: 50.00
Features\t: fp asimd
CPU implementer\t: 0x41
"""


def test_family_model_and_vector_width_tell_generations_apart():
    assert _describe(ZEN5) == "AMD EPYC (family 26 model 2, AVX-512)"  # the first processor's block only
    assert _describe(SKYLAKE) == "Intel(R) Xeon(R) Gold 6148 CPU @ 2.40GHz (family 6 model 85, AVX2)"


def test_without_x86_fields_the_name_stands_alone():
    described = _describe(ARM)
    assert described and "family" not in described and "AVX" not in described


def test_this_machine_is_described():
    assert cpu_model().strip()


def test_timed_calls_the_function_once_per_round_and_returns_medians():
    from drake_mh.study.machine import timed

    calls = []
    wall, cpu = timed(lambda: calls.append(sum(range(10_000))), 5)
    assert len(calls) == 5
    assert wall >= 0.0 and cpu >= 0.0
