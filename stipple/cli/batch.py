"""``stipple batch``: many images, each stippled as ``stipple torus`` would, here or on a Dask cluster."""

import copy
import sys
import time
from dataclasses import replace

import click

from ..errors import StippleError
from ..io.commit import check_writable, make_folder
from .defaults import INITS
from .recipes import torus_recipe
from .torus import torus
from .values import Integer

# Options of ``stipple torus`` that name one image's files or its checkpoint, or its inks: not a batch's.
NOT_BATCH = {
    "config",
    "image",
    "outputs",
    "checkpoint",
    "checkpoint_every",
    "resume",
    "palette",
    "black",
    "union_weight",
}


# The help of the copied options whose meaning differs in a batch.
BATCH_HELP = {
    "quiet": "No progress bar or summary (failed images are still reported).",
    "verbose": "Also one line per image (iterations, energy, seconds).",
    "n_points": "Number of dots of every image (-M auto is for stipple torus, one image at a time).",
}


def torus_params():
    """Copies of ``stipple torus``'s options that apply to every image of a batch (``NOT_BATCH`` left out)."""
    params = [copy.copy(param) for param in torus.params if param.name not in NOT_BATCH]
    for param in params:
        param.help = BATCH_HELP.get(param.name, param.help)
        if param.name == "n_points":
            param.type = Integer()
    return params


@click.command()
@click.argument("inputs", nargs=-1, required=True)
@click.option(
    "--out-dir",
    "-d",
    required=True,
    type=click.Path(file_okay=False),
    help="Folder of the outputs DIR/<stem>.<ext> (made if missing).",
)
@click.option(
    "--format",
    "formats",
    default="csv,png",
    show_default=True,
    help="Outputs per image: a comma-separated list of csv, png, svg.",
)
@click.option(
    "--scheduler",
    default=None,
    help="Address of a Dask distributed scheduler (tcp://host:8786): one task per image on its workers, which "
    "must see the images and DIR at the same paths. Default: here, one image after the other.",
)
@click.option("--force", is_flag=True, help="Redo every image, also those whose outputs exist.")
def batch(inputs, **options):
    """Stipple every image of INPUTS as 'stipple torus' would (the same bits for the same --seed and --threads),
    writing DIR/<stem>.<ext>. An image whose outputs all exist (and are newer than it) is skipped, so a rerun
    finishes a cut-off batch. An image that fails gets one line and the others go on; the exit status is
    100 + the number of images that failed (at most 125), 0 if none did."""
    from ..batch import exit_status, run_batch

    started = time.perf_counter()
    try:
        jobs = plan(inputs, options)
        progress = BatchProgress(len(jobs), options)
        try:
            outcomes = run_batch(jobs, progress, scheduler=options["scheduler"], force=options["force"])
        finally:
            progress.close()
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    summary(outcomes, options, started)
    sys.exit(exit_status(outcomes))


batch.params.extend(torus_params())


def plan(inputs, options):
    """The batch's jobs, every option, file and output checked before any work; makes the output folder."""
    from ..batch import cluster_client, expand_images, is_done, parse_formats, plan_batch, probe, scheduler_address
    from ..halftone import check_integer
    from ..pipelines.image import check_recipe

    if options["init"] not in INITS:
        raise StippleError(f"--init for a batch must be one of {', '.join(INITS)}, not {options['init']!r}")
    check_integer("seed", options["seed"], 0, 2**63 - 1)
    if options["order"] == "progressive":
        raise StippleError("--order progressive is for stipple torus, one image at a time; use --order here")
    formats = parse_formats(options["formats"])
    if options["scheduler"] is not None:
        _, host, port = scheduler_address(options["scheduler"])
        cluster_client()
        probe(options["scheduler"], host, port)  # an unreachable one left the -d folder made (a hostile review)
    recipe = torus_recipe(options)
    # A folder may mix images and .npy maps: --range is the maps', --levels the images'.
    recipe = replace(recipe, load={**recipe.load, "strict": False})
    check_recipe(recipe)
    out_dir = options["out_dir"]
    if not str(out_dir).strip():  # it said "Error: : cannot make the output folder"
        raise StippleError("-d: an empty folder name (an unset shell variable?)")
    jobs = plan_batch(expand_images(inputs), out_dir, formats, recipe)
    make_folder(out_dir)
    for job in jobs:
        if options["force"] or not is_done(job):
            for _, path in job.outputs:
                check_writable(path)
    return jobs


class BatchProgress:
    """The bar over images on stderr (when it is a TTY and not --quiet), and one line per failed image (always)
    and per finished one (--verbose)."""

    def __init__(self, total, options):
        self.verbose = options["verbose"] and not options["quiet"]
        self.quiet = options["quiet"]
        self.bar = None
        if not options["quiet"] and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="image", file=sys.stderr, dynamic_ncols=True)

    def __call__(self, outcome):
        if outcome.status == "failed":
            self.echo(f"stipple batch: {outcome.image}: {outcome.message}")
        elif self.verbose:
            details = f"{outcome.iterations} iterations, E={outcome.energy:.6e}, {outcome.seconds:.1f} s"
            self.echo(
                f"stipple batch: {outcome.image}: {outcome.status}" + (f"; {details}" * (outcome.status == "done"))
            )
        for note in () if self.quiet else outcome.notes:
            self.echo(f"stipple batch: {outcome.image}: note: {note}")
        if self.bar is not None:
            self.bar.update(1)

    def echo(self, line):
        if self.bar is not None:
            self.bar.write(line, file=sys.stderr)
        else:
            click.echo(line, err=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def summary(outcomes, options, started):
    """One line of counts on stderr (also under --quiet when an image failed)."""
    counts = {status: sum(outcome.status == status for outcome in outcomes) for status in ("done", "skipped", "failed")}
    if options["quiet"] and not counts["failed"]:
        return
    click.echo(
        f"stipple batch: {counts['done']} done, {counts['skipped']} skipped (outputs exist), {counts['failed']} "
        f"failed of {len(outcomes)} images; {time.perf_counter() - started:.1f} s",
        err=True,
    )
