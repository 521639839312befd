"""The pick family's scripted expert: pick up the named object, reading the simulator state.

Like Meta-World's experts it is a memoryless function of the 39-dim state vector, whose object slot
holds the named object's pose and whose goal slot the point to lift it to (:mod:`.bridge`): hover
above the object, descend with the gripper open, close until the fingers stop, lift to the goal. A
grasp that slips or misses opens the gripper and starts over.
"""

from __future__ import annotations

import numpy as np

from .catalog import LIFT_HEIGHT, LIFT_MARGIN

GAIN = 25.0  # action per metre of position error (Meta-World's experts use 10; faster here, same paths)
HOVER_Z = 0.15  # hand height while moving above the objects
MIN_HAND_Z = 0.05  # Meta-World's lowest mocap height; the fingertips are then 4.5 cm lower
ALIGNED = 0.012  # metres of xy error at which the hand starts to descend
CENTRED = 0.005  # ... and at which the fingers start to close
GRIP_OPEN = 0.85  # normalised finger distance above which the gripper counts as open
GRIP_EMPTY = 0.3  # ... and below which it closed on nothing
GRIP_STILL = 0.002  # change per step below which the fingers have stopped


class PickExpert:
    """``get_action(state) -> (dx, dy, dz, grip)`` in [-1, 1] (the interface of Meta-World's policies)."""

    def get_action(self, obs: np.ndarray) -> np.ndarray:
        hand, grip, prev_grip = obs[0:3], float(obs[3]), float(obs[21])
        target, goal = obs[4:7], obs[36:39]
        rest = goal[2] - LIFT_HEIGHT - LIFT_MARGIN  # the target's centre height when it stood on the table
        grasp_z = max(MIN_HAND_Z, rest + 0.01)
        closed = GRIP_EMPTY < grip < GRIP_OPEN
        holding = closed and (abs(grip - prev_grip) < GRIP_STILL or target[2] > rest + 0.005)
        above = np.array([target[0], target[1], grasp_z])
        xy_error = float(np.linalg.norm(hand[:2] - target[:2]))
        if holding:  # lift to the goal, keeping the grasp's height offset
            desired, effort = np.array([goal[0], goal[1], goal[2] + grasp_z - rest]), 1.0
        elif xy_error > ALIGNED:
            if xy_error > 3 * ALIGNED and hand[2] < HOVER_Z - 0.03:
                desired = np.array([hand[0], hand[1], HOVER_Z])  # rise before moving over other objects
            else:
                desired = np.array([target[0], target[1], HOVER_Z])
            effort = -1.0
        elif hand[2] > grasp_z + 0.01:  # descend once the fingers are open
            desired = above if grip > GRIP_OPEN - 0.05 else hand.copy()
            effort = -1.0
        elif grip < GRIP_EMPTY and abs(grip - prev_grip) < GRIP_STILL:  # closed on nothing: up and retry
            desired, effort = np.array([target[0], target[1], HOVER_Z]), -1.0
        elif xy_error > CENTRED and grip > GRIP_OPEN - 0.05:  # centre before closing: a finger arriving
            desired, effort = above, -1.0  # first would push the object away
        else:
            desired, effort = above, 1.0
        action = np.empty(4, dtype=np.float32)
        action[:3] = np.clip(GAIN * (desired - hand), -1.0, 1.0)
        action[3] = effort
        return action
