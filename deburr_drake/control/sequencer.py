"""The job's phases: what a whole part's run does at each moment, and the
layout of the sequencer's state (pure Python, no Drake).

A job cuts its edges in order. Each cut runs the paper's force loop on
its edge; between two cuts the tool retracts up the cut's tool axis,
moves in free space along the planned joint path and comes down the next
cut's tool axis onto its start (deburr_drake.cell.moves plans the three
as one joint path). The run ends in ``done`` when the last cut has
reached its end."""

from __future__ import annotations

from deburr_drake.control.layout import VectorLayout

__all__ = ["JOB_PHASES", "JOB_PHASE", "JOB_STATE", "JOB_COMPLETE"]

#: The phases of a job, in the order each cut goes through them; a
#: phase's code in the logs is its index here.
JOB_PHASES = ("cut", "retract", "move", "approach", "done")
#: phase name -> code.
JOB_PHASE = {name: k for k, name in enumerate(JOB_PHASES)}

#: The stop reason of a job whose every cut reached its end.
JOB_COMPLETE = "job_complete"

#: The sequencer's discrete state.
JOB_STATE = VectorLayout(
    "job_state",
    [
        ("phase", 1),  # code, index into JOB_PHASES
        ("cut", 1),  # position in the job's order of the cut under way
        # (or, on retract, move and approach, of the cut just left)
        ("phase_start", 1),  # s, when the phase began
    ],
)
