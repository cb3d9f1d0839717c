"""The table the check scripts print (scripts/tall_burr.py,
scripts/probe_checks.py): one line per figure, its value, its bound and
ok or FAIL, and the exit code: 1 when a figure misses its bound."""


def report(sections) -> int:
    """Prints ``sections`` ([(title, [(figure, value, bound, passed)])])
    and the figures that failed; returns 0 when all passed, else 1."""
    failed = []
    for title, rows in sections:
        print(title, flush=True)
        for name, value, bound, ok in rows:
            print(
                f"  {name:34s} {value:10.4g}  {bound:>16s}  "
                + ("ok" if ok else "FAIL"),
                flush=True,
            )
            if not ok:
                failed.append(f"{title}: {name}")
    if failed:
        print("failed: " + "; ".join(failed))
        return 1
    print("all checks pass")
    return 0
