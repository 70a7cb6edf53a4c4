"""Reading a run's trajectory.csv (as `ubf run --out` and `ubf sweep
--trajectories` write it) frame by frame, for the scripts that split its
end-point error.

    import trajectory_log
    for row in trajectory_log.frames("runs/route@2121/seed-100/trajectory.csv"): ...
"""
import csv


def frames(path):
    """The first row of each stereo frame that egomotion placed, by frame
    number: {frame: row}, rows as csv.DictReader gives them."""
    first = {}
    with open(path, newline='') as f:
        for row in csv.DictReader(f):
            if row['frame'] and row['ego_x']:
                first.setdefault(int(row['frame']), row)
    return first
