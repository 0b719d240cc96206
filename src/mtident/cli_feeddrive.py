"""``mtident feeddrive ...``: modes, simulation, identification of a ball-screw feed drive."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
from rich.console import Console
from rich.table import Table

from mtident.cli import OutputPath, feeddrive, number_option, print_json, table_console, user_errors
from mtident.cli_options import file_option, json_option, plot_option
from mtident.exceptions import InputError
from mtident.feeddrive import (
    IDENTIFIED,
    Excitation,
    identify_feed_drive,
    load_parameters,
    modes,
    read_response,
    simulate,
    write_response,
)
from mtident.feeddrive.identify import MEASUREMENT_SETS, PRESENT, default_guess
from mtident.feeddrive.model import EXCITATION_KINDS
from mtident.feeddrive.modes import sampling_problem
from mtident.feeddrive.params import COORDINATES, DESCRIPTIONS, UNITS, parameter_template
from mtident.feeddrive.plan import PLAN_KINDS, ExcitationPlan, candidate_tests, plan_tests

stderr = Console(stderr=True, soft_wrap=True)
params_option = file_option(
    "--params",
    "params_path",
    help="TOML parameter file (Nguyen-Quoc et al. Table 1 names, SI units); default: the shipped set.",
)

# the noise a fit assumes: identify's and plan's
fit_noise_option = number_option(
    "--noise",
    "noise_fraction",
    default=0.01,
    help="Measurement noise, fraction of each response's RMS.",
    min=0,
    min_open=True,
)


@feeddrive.command("modes")
@params_option
@json_option()
@user_errors
def modes_command(params_path: str | None, as_json: bool) -> None:
    """Natural frequencies, mode shapes and damping ratios (Nguyen-Quoc et al. Eq. 3).

    \f

    Parameters
    ----------
    params_path : str or None
        --params: a TOML parameter file (default: the shipped set).
    as_json : bool
        --json.
    """
    result = modes(load_parameters(params_path))
    if as_json:
        print_json(result.answer())
        return
    table = Table(title="Feed-drive modes (undamped; shapes mass-normalised)")
    table.add_column("mode")
    table.add_column("f (Hz)", justify="right")
    table.add_column("ζ", justify="right")
    for name in COORDINATES:
        table.add_column(name, justify="right")
    for j in range(4):
        table.add_row(
            str(j + 1),
            f"{result.frequencies_Hz[j]:.2f}",
            f"{result.damping_ratios[j]:.2e}",
            *[f"{v:+.3g}" for v in result.shapes[:, j]],
        )
    table_console().print(table)


@feeddrive.command("simulate")
@params_option
@number_option("--duration", "duration_s", default=2.0, help="Seconds.", min=0, min_open=True)
@number_option("--fs", "sample_rate_Hz", default=10_000.0, help="Sampling rate (Hz).", min=0, min_open=True)
@number_option(
    "--impulse",
    "amplitude",
    default=20.0,
    help="Force amplitude (N or N m), of every excitation; an impulse holds it for one sample: amplitude / fs.",
)
@click.option("--excitation", "kind", type=click.Choice(EXCITATION_KINDS), default="impulse", show_default=True)
@click.option(
    "--on",
    "coordinate",
    type=click.Choice(COORDINATES),
    default="table",
    show_default=True,
    help="Coordinate the force acts on (motor_rotation: motor torque T_m).",
)
@number_option(
    "--frequency",
    "frequency_Hz",
    default=100.0,
    help="Sine frequency, or the start of a sweep's or multisine's band (Hz).",
    min=0,
)
@number_option(
    "--frequency-end",
    "frequency_end_Hz",
    default=2000.0,
    help="The end of a sweep's or multisine's band, or a binary sequence's (prbs) clock (Hz).",
    min=0,
)
@number_option(
    "--noise",
    "noise_fraction",
    default=0.0,
    help="Measurement noise, fraction of each response's RMS.",
    min=0,
)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the noise generator.")
@click.option("--out", "out_path", type=OutputPath(), required=True, help="CSV to write.")
@plot_option("Draw the responses to this picture (PNG; .svg or .pdf by the suffix).")
@user_errors
def simulate_command(
    params_path: str | None,
    duration_s: float,
    sample_rate_Hz: float,
    amplitude: float,
    kind: str,
    coordinate: str,
    frequency_Hz: float,
    frequency_end_Hz: float,
    noise_fraction: float,
    seed: int,
    out_path: str,
    plot_path: str | None,
) -> None:
    """Simulate the vibration response by classical RK4 and write it as CSV.

    \f

    Parameters
    ----------
    params_path : str or None
        --params: a TOML parameter file (default: the shipped set).
    duration_s : float
        --duration (s).
    sample_rate_Hz : float
        --fs (Hz).
    amplitude : float
        --impulse: the force amplitude (N or N m).
    kind : str
        --excitation.
    coordinate : str
        --on: the coordinate the force acts on.
    frequency_Hz, frequency_end_Hz : float
        --frequency and --frequency-end (Hz).
    noise_fraction : float
        --noise: a fraction of each response's RMS.
    seed : int
        --seed.
    out_path : str
        --out: the CSV to write.
    plot_path : str or None
        --plot.

    Raises
    ------
    InputError
        Fewer than 10 samples, or an excitation above half the sampling rate.
    """
    samples = int(np.floor(duration_s * sample_rate_Hz + 1e-9)) + 1
    if samples < 10:
        msg = (
            f"--duration {duration_s:g} s at --fs {sample_rate_Hz:g} Hz gives {samples} sample(s); identification "
            "needs at least 10"
        )
        raise InputError(msg)
    # a binary sequence clocked at the sampling rate changes at most once a sample: its clock counts as twice its
    # highest
    highest = {
        "sine": frequency_Hz,
        "sweep": max(frequency_Hz, frequency_end_Hz),
        "multisine": frequency_end_Hz,
        "prbs": frequency_end_Hz / 2,
    }.get(kind, 0.0)
    if highest > sample_rate_Hz / 2:
        msg = (
            f"the {kind} reaches {highest:g} Hz, above half the sampling rate ({sample_rate_Hz / 2:g} Hz): the "
            "samples would alias it; lower the frequency or raise --fs"
        )
        raise InputError(msg)
    params = load_parameters(params_path)
    excitation = Excitation(kind, COORDINATES.index(coordinate), amplitude, frequency_Hz, frequency_end_Hz)
    response = simulate(params, excitation, sample_rate_Hz, duration_s, noise_fraction, np.random.default_rng(seed))
    write_response(response, out_path)
    stderr.print(f"mtident: wrote {len(response.time_s)} samples to {out_path}", highlight=False)
    problem = sampling_problem(params, sample_rate_Hz)
    if problem:
        stderr.print(f"mtident: note: identification will refuse this record: {problem} (raise --fs)", highlight=False)
    if plot_path:
        from mtident.report.plots import plot_responses

        plot_responses(response, plot_path, modes(params).frequencies_Hz)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)


@feeddrive.command("identify")
@click.argument("file", type=click.Path(dir_okay=False))
@file_option("--params-guess", "guess_path", help="TOML starting guess (default: the shipped set ±30 %).")
@file_option(
    "--truth",
    "truth_path",
    help="TOML true parameters (simulated data): adds the error table (Nguyen-Quoc et al. Table 3).",
)
@click.option(
    "--measured",
    type=click.Choice([PRESENT, *MEASUREMENT_SETS]),
    default=PRESENT,
    show_default=True,
    help=(
        "present: every response column the file has; all: the 12 (refused if one is missing); realistic: table "
        "acceleration + motor angle and velocity."
    ),
)
@fit_noise_option
@click.option(
    "--preset",
    type=click.Choice(["default", "paper"]),
    default="default",
    show_default=True,
    help="paper: Nguyen-Quoc et al.'s filter settings and zero variance on the parameters, so the estimate stays "
    "at --params-guess (give the true values to reproduce the paper); for comparison only.",
)
@click.option(
    "--refine/--no-refine",
    default=True,
    show_default=True,
    help=(
        "Refine the filter's estimate by fitting the whole record open loop (output-error maximum likelihood): "
        "unbiased where the filter is not (sweeps, multisines) and as precise as the record allows; kept only where "
        "it fits the record within the noise."
    ),
)
@plot_option(
    "Draw estimated vs measured responses and parameter convergence to this picture (PNG; .svg or .pdf by the suffix)."
)
@json_option()
@user_errors
def identify_command(
    file: str,
    guess_path: str | None,
    truth_path: str | None,
    measured: str,
    noise_fraction: float,
    preset: str,
    refine: bool,
    plot_path: str | None,
    as_json: bool,
) -> None:
    """Estimate stiffness and damping from a response CSV (time_s, forces, responses).

    \f

    Parameters
    ----------
    file : str
        FILE: a response CSV.
    guess_path, truth_path : str or None
        --params-guess and --truth: TOML parameter files.
    measured : str
        --measured: which responses are used.
    noise_fraction : float
        --noise: a fraction of each response's RMS.
    preset : str
        --preset.
    refine : bool
        --refine.
    plot_path : str or None
        --plot.
    as_json : bool
        --json.
    """
    response = read_response(file)
    guess = load_parameters(guess_path) if guess_path else default_guess()
    truth = load_parameters(truth_path) if truth_path else None
    steps = len(response.time_s)
    compiling = "the first run after installing also compiles the filter"
    _say_compiling(f"filtering {steps} samples")
    with stderr.status(f"filtering {steps} samples… ({compiling})") as status:
        result = identify_feed_drive(
            response,
            guess,
            measured,
            noise_fraction,
            preset,
            progress=lambda k, n: status.update(f"filtering: {k}/{n} samples"),
            refine=refine,
            refine_progress=lambda k, n: status.update(
                f"refining open loop: pass {k} over the {steps} samples (at most {n})"
            ),
        )
    for note in result.notes:
        stderr.print(f"mtident: note: {note}", highlight=False)
    if not result.identifiable.all() and preset == "default":
        hint = "`mtident feeddrive plan --params-guess FILE` says which test would identify every parameter"
        stderr.print(f"mtident: hint: {hint}", highlight=False)
    if not refine and any(note.startswith("the excitation sweeps") for note in result.notes):
        stderr.print("mtident: hint: --refine fits the record open loop, unbiased on such records", highlight=False)
    if result.reproduces_record() is False:
        hint = f"--noise sets the assumed noise ({noise_fraction:g} of each response's RMS)"
        stderr.print(f"mtident: hint: {hint}", highlight=False)
    if plot_path:
        from mtident.report.plots import plot_feed_drive_identification

        plot_feed_drive_identification(result, response, plot_path, truth)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)
    answer = result.answer(truth)
    if as_json:
        print_json(answer)
        return
    held = result.reproduces_record() is not False
    table = Table(
        title=f"{Path(file).name}: feed-drive parameters ({preset}, measured: {measured})",
        caption=None if held else "[bold yellow]The estimate does not reproduce the record: its ± 2σ do not hold.[/]",
    )
    filtered = result.filter_parameters
    columns = ("parameter", "guess", *(("filter",) if filtered is not None else ()), "estimate", "± 2σ", "identified")
    for column in (*columns, *(("true", "error %") if truth else ())):
        table.add_column(column, justify="right", no_wrap=column == "parameter")
    for i, name in enumerate(IDENTIFIED):
        known = ("yes" if held else "[yellow]doubtful[/]") if result.identifiable[i] else "[yellow]no[/]"
        estimate, half_width = f"{result.parameters[i]:.5g}", f"{2 * result.parameters_std[i]:.2g}"
        row = [f"{name} ({UNITS[name]})", f"{getattr(guess, name):.5g}"]
        row += [f"{filtered[i]:.5g}"] if filtered is not None else []
        row += [estimate, half_width, known]
        if truth and answer.error_percent is not None:
            row += [f"{getattr(truth, name):.5g}", f"{answer.error_percent[name]:.3g}"]
        table.add_row(*row)
    table_console().print(table)
    corr = Table(title="Correlation of estimated and measured responses (Nguyen-Quoc et al. Table 2)")
    corr.add_column("response")
    corr.add_column("r", justify="right")
    for name, r in result.correlation.items():
        corr.add_row(name, f"{r:.4f}")
    Console().print(corr)


@feeddrive.command("params")
@params_option
@click.option(
    "--template",
    is_flag=True,
    help="Write the set as a commented TOML file (every name, unit and meaning) to start a parameter file from.",
)
@click.option("--out", "out_path", type=OutputPath(), help="Write the template here instead of to stdout.")
@json_option()
@user_errors
def params_command(params_path: str | None, template: bool, out_path: str | None, as_json: bool) -> None:
    """The parameter names, units and values (default: Nguyen-Quoc et al.'s Table 1 with the corrected β).

    \f

    Parameters
    ----------
    params_path : str or None
        --params: a TOML parameter file (default: the shipped set).
    template : bool
        --template.
    out_path : str or None
        --out: where to write the template (default: stdout).
    as_json : bool
        --json.
    """
    params = load_parameters(params_path)
    if template:
        text = parameter_template(params)
        if out_path:
            Path(out_path).write_text(text, encoding="utf-8")
            stderr.print(f"mtident: wrote the parameter template to {out_path}", highlight=False)
        else:
            click.echo(text, nl=False)
        return
    if as_json:
        print_json({"parameters": params.as_dict(), "units": dict(UNITS), "identified": list(IDENTIFIED)})
        return
    table = Table(title="Feed-drive parameters (SI units; TOML names)")
    for column in ("name", "value", "unit", "meaning", "identified"):
        table.add_column(column)
    for name, value in params.as_dict().items():
        table.add_row(name, f"{value:.6g}", UNITS[name], DESCRIPTIONS[name], "yes" if name in IDENTIFIED else "known")
    table_console().print(table)


def _positive_list(text: str, option: str, example: str) -> tuple[float, ...]:
    msg = f"{option}: expected comma-separated positive numbers such as {example}; found {text!r}"
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError as exc:
        raise InputError(msg) from exc
    if not values or any(not (v > 0 and np.isfinite(v)) for v in values):
        raise InputError(msg)
    return values


@feeddrive.command("plan")
@file_option(
    "--params-guess",
    "guess_path",
    help="TOML: the best knowledge of the drive, e.g. an earlier estimate (default: the shipped set).",
)
@click.option(
    "--excitation", "kinds", type=click.Choice(PLAN_KINDS), multiple=True, help="Candidate (repeat; default: all)."
)
@click.option(
    "--on",
    "places",
    type=click.Choice(COORDINATES),
    multiple=True,
    help="Where the force acts (repeat; default: table and motor_rotation, i.e. table force and motor torque).",
)
@click.option("--durations", default="0.25,0.5,1,2", show_default=True, help="Test durations (s), comma-separated.")
@click.option("--fs", "rates", default="10000", show_default=True, help="Sampling rates (Hz), comma-separated.")
@click.option(
    "--measured",
    type=click.Choice(list(MEASUREMENT_SETS)),
    default="all",
    show_default=True,
    help="all: the 12 responses; realistic: table acceleration + motor angle and velocity.",
)
@fit_noise_option
@number_option(
    "--target",
    default=0.10,
    help="Identified: the stated ±2σ within this fraction of the value.",
    min=0,
    min_open=True,
    max=1,
)
@click.option(
    "--refine/--no-refine",
    default=True,
    show_default=True,
    help="Predict the estimate refined open loop, as identify gives it by default (--no-refine: the filter's own).",
)
@json_option()
@user_errors
def plan_command(
    guess_path: str | None,
    kinds: tuple[str, ...],
    places: tuple[str, ...],
    durations: str,
    rates: str,
    measured: str,
    noise_fraction: float,
    target: float,
    refine: bool,
    as_json: bool,
) -> None:
    """Which test identifies all eight parameters: the expected standard deviations for candidate
    excitations, from the Fisher information of the model at the guess, and the cheapest that does.

    \f

    Parameters
    ----------
    guess_path : str or None
        --params-guess: a TOML parameter file (default: the shipped set).
    kinds : tuple of str
        --excitation (empty: every kind).
    places : tuple of str
        --on (empty: table force and motor torque).
    durations : str
        --durations: seconds, comma-separated.
    rates : str
        --fs: sampling rates (Hz), comma-separated.
    measured : str
        --measured.
    noise_fraction : float
        --noise: a fraction of each response's RMS.
    target : float
        --target: a fraction of each parameter's value.
    refine : bool
        --refine.
    as_json : bool
        --json.

    Raises
    ------
    InputError
        --durations or --fs not comma-separated positive numbers.
    """
    guess = load_parameters(guess_path)
    candidates = candidate_tests(
        guess,
        kinds or PLAN_KINDS,
        tuple(COORDINATES.index(p) for p in places) or (0, 3),
        _positive_list(durations, "--durations", "0.5,1,2"),
        _positive_list(rates, "--fs", "10000,20000"),
        measured,
    )
    _say_compiling(f"predicting {len(candidates)} tests")
    with stderr.status(f"predicting {len(candidates)} tests…"):
        plan = plan_tests(guess, candidates, noise_fraction, target, refine=refine)
    if as_json:
        print_json(plan.answer())
        return
    _print_plan(plan, measured)


def _print_plan(plan: ExcitationPlan, measured: str) -> None:
    whose = (
        "the refined estimate's stated ±2σ (%) after each test"
        if plan.refine
        else "the filter's stated ±2σ (%) after each test; repeated tests scatter less (--json)"
    )
    table = Table(title=f"{whose[0].upper()}{whose[1:]}; measured: {measured}, noise {plan.noise_fraction:g}")
    table.add_column("test")
    for name in IDENTIFIED:
        table.add_column(name, justify="right")
    for p in plan.predictions:
        cells = [
            f"{200 * s:.2g}" if ok else f"[yellow]{200 * s:.2g}[/]"
            for s, ok in zip(p.stated_std_log, p.identified, strict=True)
        ]
        label = p.candidate.label + (f" [dim]({p.reason.split(':')[0]})[/]" if p.reason else "")
        table.add_row(("[bold]" + label + "[/]") if p is plan.recommended else label, *cells)
    table_console(140).print(table)
    within = f"within ±{100 * plan.target:g} %"
    best = plan.closest
    if best is not None and best.force_noise_tolerated is not None:
        tolerated = best.force_noise_tolerated
        level = "any" if not np.isfinite(tolerated) else f"up to {100 * tolerated:.2g} % of its RMS"
        stderr.print(
            f"mtident: {best.candidate.label} keeps what it identifies {within} with white noise on the "
            f"measured force {level} (a force sensor's or a motor current's; more widens the intervals)",
            highlight=False,
        )
    if plan.recommended is not None and plan.recommended is plan.lengthened:
        stderr.print(
            f"mtident: no test of the durations asked identifies all eight {within}; recommended, the most "
            f"informative broadband one run longer: {plan.recommended.candidate.label}",
            highlight=False,
        )
        return
    if plan.recommended is not None:
        chosen = plan.recommended.candidate.label
        line = f"mtident: recommended (the cheapest that identifies all eight {within}): {chosen}"
        stderr.print(line, highlight=False)
        return
    allowed = [p for p in plan.predictions if p.reason is None]
    never = [name for j, name in enumerate(IDENTIFIED) if not any(p.identified[j] for p in allowed)]
    closest = (
        ""
        if plan.closest is None
        else (
            f"; the closest: {plan.closest.candidate.label} (widest ±2σ: "
            f"{200 * plan.closest.stated_std_log.max():.3g} %)"
        )
    )
    stderr.print(
        f"mtident: no candidate identifies all eight {within}; never within it: {', '.join(never) or 'none'}"
        f"{closest}; longer --durations, finer sensors (--noise) or another --measured set may identify them",
        highlight=False,
    )


def _say_compiling(doing: str) -> None:
    """Say, off a terminal, that the compiled loops are compiled first: a spinner shows on a
    terminal alone, and elsewhere (a pipe, a CI log) a minute passed without a word."""
    from mtident.feeddrive import fast

    if not fast.compiled_cache_ready() and not stderr.is_terminal:
        stderr.print(
            f"mtident: {doing}: compiling the filter first (once after installing: about a minute)", highlight=False
        )
