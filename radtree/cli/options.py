"""Options and settings shared by several commands."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import click

CONTEXT: dict[str, Any] = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


def scenarios_option(f: Callable[..., Any]) -> Callable[..., Any]:
    """``-s/--scenario`` (repeatable) → a tuple ``scenarios``."""
    return click.option("-s", "--scenario", "scenarios", multiple=True,
                        help="Only this scenario (repeatable). Default: all.")(f)


def wait_option(f: Callable[..., Any]) -> Callable[..., Any]:
    """``--wait``: when another radtree run writes the same folder, wait for it (else exit 2)."""
    return click.option("--wait", is_flag=True,
                        help="If another radtree run is writing the same folder, wait for it "
                             "to finish instead of stopping.")(f)


@contextmanager
def writing(folders: list[Path], project: str, wait: bool) -> Iterator[None]:
    """Hold the lock of every output folder in ``folders`` (:mod:`radtree.lock`) while inside;
    the lock names this command (``radtree NAME PROJECT``) to a second run."""
    from radtree.lock import folder_lock

    ctx = click.get_current_context()
    command = f"radtree {ctx.info_name} {project}"
    with ExitStack() as stack:
        for folder in folders:
            stack.enter_context(folder_lock(folder, command, wait=wait))
        yield


def writes(*folders: str, out_param: str | None = None
           ) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """A command writing ``PROJECT/<folder>`` for each of ``folders`` (or the folder given by
    its ``out_param`` option): adds ``--wait`` and holds those folders' locks while it runs,
    so a second run on the same project is refused (exit 2) naming the first, or waits."""
    def decorate(f: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(f)
        def run(*args: Any, **kwargs: Any) -> Any:
            wait = kwargs.pop("wait")
            project = kwargs.get("project")
            if project is None:
                return f(*args, **kwargs)
            from radtree.config.reader import find_project_file

            root = find_project_file(project).parent
            dirs = [root / name for name in folders]
            if out_param is not None and kwargs.get(out_param):
                dirs = [Path(kwargs[out_param])]
            with writing(dirs, str(project), wait):
                return f(*args, **kwargs)

        return wait_option(run)

    return decorate
