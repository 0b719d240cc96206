"""`mtident thermal report`: a finished or stopped warm-up test written up as HTML or PDF."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from mtident.cli import as_options, stderr, thermal, user_errors
from mtident.cli_logs import asked_sensors, log_options, log_path, say_room_candidates, unread_rooms_of
from mtident.cli_options import file_option, output_option
from mtident.cli_watch import decision_options, monitor_settings, state_file, workbook_as_replayed_csv
from mtident.exceptions import InputError
from mtident.thermal.monitor import minutes
from mtident.thermal.session import WatchSession

REPORT_FORMATS = (".html", ".htm", ".pdf")


@thermal.command("report")
@log_options
@decision_options
@output_option("The report: .html (one self-contained page, the figure embedded) or .pdf (A4).")
@file_option(
    "--state",
    "state_path",
    help="The state file of a watch of this log, to start from (default: beside the log, LOG.watch-state.npz).",
)
@user_errors
def report_command(**options: Any) -> None:
    """Write up a finished or stopped warm-up test of FILE for the customer.

    The report names the machine and program (--machine, or the reference run's) and when the
    test began (the log's time stamps, or a recorder's first reading), says the decision and,
    where the test could not stop, what holds it, a line per sensor; then per sensor T∞ with its
    95 % interval, t_eq and the measured curve with the predicted one, the check against the rest
    of the log where the log runs on (where the readings settled, and the time the stop saved),
    the warnings, what the answer assumes, the method and the software version. The decision is
    the one `thermal watch` reaches with the same options; where a watch of this log left its
    state file, the report starts from it.

    \f

    Parameters
    ----------
    **options
        The options by click's names, each with its help above.

    Raises
    ------
    InputError
        An -o that is not .html or .pdf, or no such log.
    """
    file, output_path = options["file"], options["output_path"]
    output = Path(output_path)
    if output.suffix.lower() not in REPORT_FORMATS:
        msg = f"-o {output_path}: the report is written as HTML or PDF; give a name ending in .html or .pdf"
        raise InputError(msg)
    path = log_path(file)
    if not path.is_file():
        msg = f"{path}: no such file"
        raise InputError(msg)
    settings = monitor_settings(options)
    read, sheet_read, sheet_notes = workbook_as_replayed_csv(path, options["sheet"])
    session = WatchSession(
        read,
        settings,
        sensors=asked_sensors(options["sensors"], path, options["sheet"]) or None,
        time_col=options["time_col"],
        time_unit=options["time_unit"],
        temperature_unit=options["temperature_unit"],
        state_path=state_file(file, path, options["state_path"], options["sheet"]),
        persist=False,  # a watch may still follow this log: its state file is its own
        shown_as=path,  # a workbook is read as a temporary copy of the CSV it holds: the report names the workbook
        sheet=sheet_read,
    )
    for note in session.notes:
        stderr.print(f"mtident: {note}", highlight=False)
    for note in sheet_notes:
        stderr.print(f"mtident: warning: {note}", highlight=False)
    from mtident.report.report_render import write_html, write_pdf
    from mtident.report.test_report import build_report

    with stderr.status("reading the log…") as status:

        def progress(current: WatchSession) -> None:
            if current.state is not None:
                status.update(f"deciding: t = {minutes(current.state.readings.latest_min)} of the log")

        report = build_report(session, progress, options["machine"])
    # the page says the command line's options, as its stderr does, not the library's parameters
    report = report.reworded(as_options)
    # what reading the log said, as a watch says it (the report holds it too)
    for note in report.log_notes:
        stderr.print(f"mtident: note: {note}", highlight=False)
    for warning in report.log_warnings:
        stderr.print(f"mtident: warning: {warning}", highlight=False)
    if settings.room_sensor is None:  # as watch says it: a room column was reported as a machine sensor, or not read
        unread = unread_rooms_of(read, session.sensors) if session.asked is not None else []
        say_room_candidates(session.sensors, "reported as a machine sensor", unread=unread)
    written = write_pdf(report, output) if output.suffix.lower() == ".pdf" else write_html(report, output)
    verdict = (
        f"the test could stop at t = {minutes(report.stop_time_min)}"
        if report.decision == "stop"
        else "no stop within the log"
    )
    click.echo(f"{written}: {verdict}")
