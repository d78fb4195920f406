"""The fleet diagnosis (``zrp diagnose --data 'fleet/*.csv'``): one diagnosis per measurement
file on a Dask cluster or in this process (:mod:`.run`), each robot's report in its own folder,
and a fleet summary - which robots are out of tolerance, which effect dominates
(:mod:`.summary`). The unit of work is :mod:`.tasks`."""

from zrp.cli.fleet.run import FLEET_FILES as FLEET_FILES
from zrp.cli.fleet.run import add_fleet_options as add_fleet_options
from zrp.cli.fleet.run import is_fleet as is_fleet
from zrp.cli.fleet.run import refuse_fleet_options as refuse_fleet_options
from zrp.cli.fleet.run import run_fleet as run_fleet

__all__ = [
    "FLEET_FILES",
    "add_fleet_options",
    "is_fleet",
    "refuse_fleet_options",
    "run_fleet",
]
