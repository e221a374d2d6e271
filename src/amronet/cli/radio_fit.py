"""The ``amronet radio-fit`` subcommand: a radio model calibrated on measured RSSI.

``amronet radio-fit --map flat.yaml --anchors anchors.csv --rssi rssi.csv [--model multi-wall|log-distance|all]
[--per-anchor] [--tag-height 1.3] [--bootstrap 200] [--folds 5] [--block-m M] [--seed 0] [--floor-dbm DBM]
[--out DIR] [--no-pictures] [-q]`` fits the model's parameters with bootstrap intervals, compares the models by
cross-validation over blocks of positions and over single positions, prints the result and the
``--set radio.KEY=VALUE`` lines of the fitted radio, and with ``--out`` writes ``fit.json``, ``radio.yaml`` and
pictures (an amronet output folder, replaced atomically).
Bad input raises :class:`amronet.errors.AmronetError` with one line naming the option, and nothing is written.
"""

from __future__ import annotations

import argparse

from amronet.errors import AmronetError

__all__ = ["add_parser", "cmd_radio_fit"]


def _check(args: argparse.Namespace) -> None:
    import math

    if not 2 <= args.folds <= 100:
        raise AmronetError(f"--folds: {args.folds} must be a whole number from 2 to 100, e.g. 5")
    if not 10 <= args.bootstrap <= 10000:
        raise AmronetError(f"--bootstrap: {args.bootstrap} must be a whole number from 10 to 10000, e.g. 200")
    if args.seed < 0:
        raise AmronetError(f"--seed: {args.seed} must be a whole number >= 0")
    if not math.isfinite(args.tag_height) or not 0 <= args.tag_height <= 100:
        raise AmronetError(f"--tag-height: {args.tag_height:g} must be a height in metres from 0 to 100, e.g. 1.3")
    if args.block_m is not None and (not math.isfinite(args.block_m) or not 0 < args.block_m <= 1000):
        raise AmronetError(f"--block-m: {args.block_m:g} must be a side in metres above 0 and up to 1000, e.g. 2")
    if args.floor_dbm is not None and not -174 <= args.floor_dbm <= 60:
        raise AmronetError(f"--floor-dbm: {args.floor_dbm:g} must be a level in dBm from -174 to 60, e.g. -93")


def cmd_radio_fit(args: argparse.Namespace) -> int:
    """Run ``amronet radio-fit`` (see the module docstring)."""
    from amronet.outputs.files import check_output_folder

    _check(args)
    if args.out is not None:  # before the work: a folder holding a user's files is refused, untouched
        check_output_folder(args.out)
    from amronet.radiofit import FitOptions, fit_dict, fit_radio, fit_text, load_readings, write_fit
    from amronet.radiofit.writing import FILES, attribution_beside
    from amronet.world.builtin import resolve_map

    omap = resolve_map(args.map)
    readings = load_readings(omap, args.anchors, args.rssi, args.tag_height)
    models = ("log-distance", "multi-wall") if args.model == "all" else (args.model,)
    opt = FitOptions(models=models, per_anchor=args.per_anchor, n_boot=args.bootstrap, folds=args.folds,
                     seed=args.seed, floor_dbm=args.floor_dbm, block_m=args.block_m)
    rf = fit_radio(readings, opt)
    data = {"map": str(args.map), "anchors": str(args.anchors), "rssi": str(args.rssi)}
    attribution = args.attribution or attribution_beside(args.rssi)
    if attribution:
        data["attribution"] = attribution
    doc = fit_dict(rf, data)
    if args.out is not None:
        write_fit(rf, doc, omap, args.out, pictures=not args.no_pictures)
    if not args.quiet:
        print(fit_text(rf), end="")
        if args.out is not None:
            from amronet.outputs.console import folder_name

            names = FILES if not args.no_pictures else FILES[:2]
            print(f"wrote {folder_name(args.out)}: {' '.join(names)}")
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``radio-fit`` on the ``amronet`` subparsers."""
    p = subparsers.add_parser(
        "radio-fit", help="calibrate a radio model (log-distance, multi-wall) on measured RSSI",
        description="Fit amronet's path-loss laws to measured RSSI readings on a map: parameters with bootstrap "
                    "intervals over positions, k-fold cross-validated RMSE per model (over blocks of positions and "
                    "over single positions), the shadowing's spread and correlation distance (variogram), the "
                    "effect of the receivers' floor, and a radio: block that reproduces the fit through amronet's "
                    "own link budget.")
    p.add_argument("--map", required=True, help="the floor map: ROS map_server YAML or a built-in map's name")
    p.add_argument("--anchors", required=True, help="CSV id,x,y[,z]: the fixed receivers (z: height, m)")
    p.add_argument("--rssi", required=True,
                   help="CSV x,y,anchor,rssi_dbm[,point]: one row per reading (point: the measurement it belongs "
                        "to; then the anchors without a row there are known not to have heard it)")
    p.add_argument("--model", choices=("multi-wall", "log-distance", "all"), default="multi-wall",
                   help="the model to fit in detail (default multi-wall); all: both, radio.yaml takes the one with "
                        "the lower cross-validated RMSE")
    p.add_argument("--per-anchor", action="store_true", help="one constant A = tx - PL0 per anchor")
    p.add_argument("--tag-height", type=float, default=1.3,
                   help="height of the transmitting tag above the floor in metres (default 1.3, the BLE flat "
                        "data set's); lengths are 3-D from the anchors' z")
    p.add_argument("--bootstrap", type=int, default=200, help="bootstrap resamples over positions (default 200)")
    p.add_argument("--folds", type=int, default=5, help="cross-validation folds over positions (default 5)")
    p.add_argument("--block-m", type=float,
                   help="side in metres of the square blocks of positions that cross-validation holds out together "
                        "(default: 3 x the correlation distance of the multi-wall fit's residuals)")
    p.add_argument("--seed", type=int, default=0, help="seed of the folds and the bootstrap (default 0)")
    p.add_argument("--floor-dbm", type=float,
                   help="the receivers' floor in dBm (default: the weakest reading); also radio.yaml's threshold")
    p.add_argument("--attribution", help="source and licence of the data, kept in fit.json and radio.yaml "
                                         "(default: the Attribution line of a README.md beside --rssi)")
    p.add_argument("--out", help="folder to write fit.json, radio.yaml and the pictures into")
    p.add_argument("--no-pictures", action="store_true", help="write no pictures")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing")
    p.set_defaults(func=cmd_radio_fit)
