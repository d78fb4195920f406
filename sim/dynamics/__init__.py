"""The dynamic gap: where a MuJoCo model's joint torques miss a real arm's logged torques,
which unmodelled effect causes it, and how far the withheld torque error shrinks once it is
added (see README.md)."""
