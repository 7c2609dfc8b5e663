"""``camjax sweep``: a large law x period-ratio x damping grid from a TOML spec file."""

from __future__ import annotations

import sys

from ._common import CliError, output_dir


def register(sub) -> None:
    parser = sub.add_parser(
        "sweep",
        help="run a large sweep from a TOML spec: resumable chunks, many devices or hosts",
        description="Compute Ct, residual and peak in motion for every law of a spec file "
        "(named laws and/or an SCCA grid) at every period ratio and damping ratio.  Chunks "
        "are written atomically to the output directory; rerunning the same command "
        "computes only the missing ones.  The spec format (every key, its default, the "
        "files written) is in docs/sweep.md.",
    )
    parser.add_argument("spec", metavar="SPEC", help="TOML spec file")
    parser.add_argument("--devices", type=int, metavar="K",
                        help="local devices to split each chunk over (default: all; on a CPU, "
                        "a single-process run has one device per core, as a power of two up "
                        "to 64)")
    parser.add_argument("--coordinator", metavar="HOST:PORT",
                        help="coordinator of a multi-process run (process 0's address)")
    parser.add_argument("--num-processes", type=int, metavar="P", help="processes in the run")
    parser.add_argument("--process-id", type=int, metavar="I", help="this process, 0..P-1")
    parser.add_argument("--distributed", action="store_true",
                        help="join a multi-process run, letting JAX detect the cluster")
    parser.set_defaults(func=run)


def run(args) -> int:
    from .. import distributed

    given = [x is not None for x in (args.coordinator, args.num_processes, args.process_id)]
    if any(given) and not all(given):
        raise CliError("--coordinator, --num-processes and --process-id go together")
    if all(given) or args.distributed:
        if all(given) and not 0 <= args.process_id < args.num_processes:
            raise CliError(f"--process-id must be in 0..{args.num_processes - 1}")
        distributed.initialize(args.coordinator, args.num_processes, args.process_id)
    else:  # one process: a CPU device per core, each chunk split over them
        from ..sharding import available_cores, use_cpu_cores

        # A power of two (at most 64) splits the default chunk of 64 laws without padding.
        count = min(64, 1 << (available_cores().bit_length() - 1))
        try:
            use_cpu_cores(count)
        except RuntimeError:  # JAX already started (main() called from Python): keep its devices
            pass
    spec = distributed.load_spec(args.spec)  # after initialize: building laws starts JAX
    output_dir(str(spec.output), f"{args.spec}: output")  # writable, before any work
    if args.devices is not None:
        import jax

        count = jax.local_device_count()
        if not 1 <= args.devices <= count:
            raise CliError(f"--devices: must be between 1 and the {count} local device(s), "
                           f"got {args.devices}")
    path = distributed.run_distributed(spec, devices=args.devices)
    if path is not None:
        import jax

        used = args.devices or jax.local_device_count()
        print(f"wrote {path} ({len(spec.laws)} laws x {spec.period_ratio.size} period ratios "
              f"x {len(spec.damping)} damping ratios, on {used} local device(s))", file=sys.stderr)
    return 0
