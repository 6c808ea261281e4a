"""``jaxspline view PLAN.json``: rebuild the plan's web page from an existing ``plan.json``.

Reads the plan document that ``jaxspline plan`` wrote (with its ``"view"`` section:
ground tracks, targets, footprints, areas, battery; :mod:`jaxspline.products.plan_view`) and
writes the self-contained page (:mod:`jaxspline.products.plan_html`), by default ``plan.html``
next to it. Nothing is re-planned. An existing page is never overwritten unless
``--force``; the file is written atomically.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from jaxspline.cli.flags import check_output_file, check_path

__all__ = ["read_plan_file", "register", "run_view"]


def register(sub) -> None:
    """Register the ``view`` sub-command.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser(
        "view",
        help="rebuild the web page (plan.html) of a plan from its plan.json",
        description=__doc__,
    )
    p.add_argument("plan", help="plan.json written by jaxspline plan")
    p.add_argument(
        "-o", "--output", default=None, help="page to write (default: plan.html next to PLAN)"
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing page")
    p.set_defaults(func=_main)


def _main(args) -> int:
    path = run_view(args.plan, args.output, force=args.force)
    print(f"page          {path}", file=sys.stdout)
    return 0


def read_plan_file(plan: Path) -> dict:
    """The checked document of a ``plan.json`` (:func:`jaxspline.cli.plan_file.check_plan_doc`).

    Args:
      plan: Path of the file.
    Returns:
      dict.
    Raises:
      FileNotFoundError: no such file.
      ValueError: not readable UTF-8 JSON, or a field the page reads is malformed.
    """
    from jaxspline.cli.plan_file import check_plan_doc
    from jaxspline.readers.fields import read_text

    try:
        text = read_text(plan)
    except FileNotFoundError:
        raise FileNotFoundError(f"plan file not found: {plan}") from None
    try:
        doc = json.loads(text)
    except ValueError as exc:  # JSONDecodeError, or an integer of over 4,300 digits
        raise ValueError(f"{plan}: not JSON this reader takes ({exc})") from None
    except RecursionError:
        raise ValueError(f"{plan}: not JSON this reader takes (nested too deeply)") from None
    return check_plan_doc(doc, str(plan))


def run_view(plan, output=None, *, force: bool = False) -> Path:
    """Write the page of a ``plan.json``.

    Args:
      plan: str or Path of the plan document.
      output: str or Path of the page; None: ``plan.html`` in the plan's folder.
      force: overwrite an existing page.
    Returns:
      Path of the page.
    Raises:
      FileNotFoundError: no such plan file.
      FileExistsError: the page exists and ``force`` is false.
      ValueError: the file is not a plan document (naming the file and the field), or a
        flag is bad.
    """
    from jaxspline.products.plan_html import HTML_FILE, write_plan_html

    check_path("PLAN", str(plan), kind="file")
    check_path("-o/--output", None if output is None else str(output), kind="file")
    plan = Path(plan)
    out = plan.parent / HTML_FILE if output is None else Path(output)
    doc = read_plan_file(plan)  # the input's own errors first (reading it is instant)
    check_output_file("-o/--output", str(out), force=force)
    try:
        return write_plan_html(doc, out, force=force)
    except (KeyError, TypeError, IndexError, AttributeError, ValueError) as exc:
        # a field the checks let through that the page cannot draw
        raise ValueError(f"{plan}: cannot draw this plan ({type(exc).__name__}: {exc})") from None
