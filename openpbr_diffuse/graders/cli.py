"""``openpbr-diffuse check`` options that run an implementation's own code (hooked by cli/check.py).

    openpbr-diffuse check --implementation NAME [--source PATH] [--json]
    openpbr-diffuse check --glsl FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]
    openpbr-diffuse check --cpp FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]

Exit status: 0 every graded quantity conforms, 1 one does not, 2 a piece is missing (GL driver,
compiler, bpy, source files) or the code does not compile.
"""
from __future__ import annotations

import json


def add_arguments(parser):
    """Add the grader options to the ``check`` sub-command's parser."""
    from . import IMPLEMENTATIONS

    g = parser.add_argument_group(
        "grade an implementation by running its own code",
        "--glsl and --cpp compile and run the given code with your user's rights (C++ under a time "
        "and memory limit, in a process group that is killed on timeout or Ctrl-C)")
    g.add_argument("--implementation", choices=sorted(IMPLEMENTATIONS), metavar="NAME",
                   help="one of: " + ", ".join(IMPLEMENTATIONS))
    g.add_argument("--source", metavar="PATH", help="the implementation's checkout (its code is not in a package)")
    g.add_argument("--glsl", metavar="FILE", help="a GLSL file holding FUNCTION (see --function)")
    g.add_argument("--cpp", metavar="FILE", help="a C++ file holding FUNCTION (see --function)")
    g.add_argument("--function", metavar="NAME",
                   help="BRDF function: vec3 NAME(vec3 wi, vec3 wo, float roughness, vec3 rho), local frame, no cosine")
    g.add_argument("--albedo-function", metavar="NAME",
                   help="albedo function: vec3 NAME(float mu, float roughness, vec3 rho)")
    g.add_argument("--include", metavar="DIR", action="append", default=[], help="include path (repeatable)")
    g.add_argument("--define", metavar="NAME=VALUE", action="append", default=[],
                   help="preprocessor define (repeatable)")
    g.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="wall-time limit of each compile and run of the C++ code (default 60)")
    g.add_argument("--quick", action="store_true", help="fewer sampler samples (40k instead of 200k per case)")


def _print_text(result):
    print(f"{result.name}: {'CONFORMS' if result.passed else 'DOES NOT CONFORM'} (reference model {result.model})")
    for k, v in result.version.items():
        if v not in (None, "", [], {}):
            print(f"  {k}: {v if not isinstance(v, list) else ', '.join(map(str, v))}")
    for q in result.quantities:
        verdict = "pass" if q.passed else "FAIL"
        print(f"  {q.quantity:30s} {verdict}  max {q.max_abs_error:.3g}  rms {q.rms_error:.3g}  "
              f"[{q.tolerance}]" + (f"  ({q.excluded} rows outside its input domain)" if q.excluded else ""))
        if q.diagnosis or not q.passed:
            print(f"      diagnosis: {q.diagnosis or 'none'} -- {q.detail}")
        else:
            print(f"      {q.detail}")
    for note in result.notes:
        print(f"  note: {note}")


def subject_from_args(args):
    """The :class:`~.subject.Subject` the options name, or None when no implementation option is given.

    Used by ``check`` and by ``report``; raises ``ValueError`` for contradictory options and
    :class:`~.errors.GraderUnavailable` when a piece (GL driver, compiler, source) is missing.
    """
    from . import load
    from .generic import cpp_subject, glsl_subject

    cmd = "check" if getattr(args, "file", None) is not None or not hasattr(args, "out") else "report"
    modes = [m for m in ("implementation", "glsl", "cpp") if getattr(args, m, None)]
    if not modes:
        for opt in ("source", "function", "albedo_function"):
            if getattr(args, opt, None):
                raise ValueError(f"{cmd}: --{opt.replace('_', '-')} needs --implementation, --glsl or --cpp")
        return None
    if len(modes) > 1 or getattr(args, "file", None):
        raise ValueError(f"{cmd}: give one of FILE, --implementation, --glsl, --cpp")
    if args.implementation:
        if args.function or args.albedo_function:
            raise ValueError(f"{cmd}: --function is for --glsl / --cpp, not --implementation")
        return load(args.implementation, args.source)
    if args.source:
        raise ValueError(f"{cmd}: --source is for --implementation")
    if args.glsl:
        return glsl_subject(args.glsl, args.function, args.albedo_function, includes=args.include or (),
                            defines=args.define or (), model=args.model or "eon")
    return cpp_subject(args.cpp, args.function, args.albedo_function, includes=args.include or (),
                       defines=args.define or (), model=args.model or "eon", timeout=getattr(args, "timeout", None))


def run(args):
    """Grade per the options, or return None when none of them is given (``check FILE`` mode)."""
    from .grading import grade_subject

    subject = subject_from_args(args)
    if subject is None:
        return None
    result = grade_subject(subject, quick=args.quick)  # GraderUnavailable (an OSError): exit 2
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        _print_text(result)
    return 0 if result.passed else 1
