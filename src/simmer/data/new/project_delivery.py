"""MIE444 project, phases 2 and 3, written the way a team writes it: plain sockets on SimMeR's
two ports, the target zone typed at a prompt, the gripper's command sent like any other.

From the lab's start ([6, 42], facing the loading zone) it drives into the loading zone, finds
the block with two ultrasonic sensors at different heights (the low one, u4, sees the block; the
high one, u0, sees over it), picks it up, asks which drop-off zone to deliver to and drives
there through the maze. Phase 1 (finding where the robot is) is the team's own: this program
knows its start and counts its moves (the example configuration has no noise).

    simmer run examples/project.toml                  # then, in another terminal:
    python examples/project_delivery.py               # and type B1, B2, B3 or B4

or in one go, the answer typed for it, as fast as the machine goes:

    simmer run examples/project.toml --headless --answer "{target}" \
        --program "python examples/project_delivery.py"
"""

import math
import os
import socket
import struct
import time
from collections import deque

HOST = os.environ.get("SIMMER_HOST") or "127.0.0.1"
# SimMeR's ports, 61200 and 61201 unless SIMMER_PORTS moves them (as it does every simmer
# command's): "62000" for 62000, 62001, 62002, or three ports "RX,TX,PORT"
PORTS = [int(port) for port in os.environ.get("SIMMER_PORTS", "61200").split(",")]
PORT_TX = PORTS[0]  # the client transmits here (the simulator's port_rx)
PORT_RX = PORTS[1] if len(PORTS) == 3 else PORTS[0] + 1  # the client receives here (port_tx)

WALLS = [[3, 3, 1, 1, 0, 2, 0, 2],
         [3, 3, 0, 1, 1, 1, 1, 1],
         [1, 0, 2, 0, 0, 1, 0, 1],
         [1, 1, 1, 1, 1, 1, 0, 2]]  # fmt: skip
CELL = 12.0
ZONES = {"B1": (0, 5), "B2": (0, 7), "B3": (2, 2), "B4": (3, 7)}  # row, column
SENSOR_AHEAD = 1.0  # u0 and u4 sit 1 in ahead of the robot's centre, at the back of the mouth
BLOCK = 3.0
HALF_WIDTH = 2.875  # half the robot's width
TURNING = 5.0  # the robot turns in place this far from a wall at least
SEES_BLOCK = 2.0  # the low sensor reads this much less than the high one: the block is there

# where the robot is: x, y in inches, heading in degrees (0 = +y, 90 = -x, 180 = -y)
pose = {"x": 6.0, "y": 42.0, "heading": 180.0}


# ---------------------------------------------------------------- talking to the robot


def transmit(data):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.connect((HOST, PORT_TX))
        s.sendall(data.encode("utf-8"))


def receive():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.connect((HOST, PORT_RX))
        raw = b""
        while chunk := s.recv(1024):
            raw += chunk
    return [v for (v,) in struct.iter_unpack("<f", raw)]


def send(data):
    transmit(data)
    return receive()


def wait_until_stopped():
    while not math.isinf(send("w0-0")[0]):
        time.sleep(0.05)


def forward(distance):
    if abs(distance) < 0.01:
        return
    send(f"w0-{distance:.3f}")
    time.sleep(abs(distance) / 6)  # 6 in/s
    wait_until_stopped()
    pose["x"] += -math.sin(math.radians(pose["heading"])) * distance
    pose["y"] += math.cos(math.radians(pose["heading"])) * distance


def turn(degrees):
    if abs(degrees) < 0.01:
        return
    send(f"r0-{degrees:.3f}")
    time.sleep(abs(degrees) / 120)  # 120 deg/s
    wait_until_stopped()
    pose["heading"] = (pose["heading"] + degrees) % 360


def face(new_heading):
    turn((new_heading - pose["heading"] + 180) % 360 - 180)


def read():
    high, low = send("u0,u4")
    return high, low


# ---------------------------------------------------------------- phase 2: the block


def scan(start, stop, step):
    """Turn from heading start to stop, reading both sensors; where the block is seen, the
    middle heading of the sighting and the nearest low reading (None if not seen)."""
    seen = []
    face(start)
    h = start
    while (stop - h) * step >= 0:
        face(h % 360)
        high, low = read()
        if low < high - SEES_BLOCK:
            seen.append((h, low))
        h += step
    if not seen:
        return None
    middle = (seen[0][0] + seen[-1][0]) / 2
    return middle % 360, min(low for _, low in seen)


def block_place(sighting):
    """Where the block's centre is, from a sighting taken here."""
    h, distance = sighting
    sx = pose["x"] - math.sin(math.radians(pose["heading"])) * SENSOR_AHEAD
    sy = pose["y"] + math.cos(math.radians(pose["heading"])) * SENSOR_AHEAD
    reach = distance + BLOCK / 2
    return sx - math.sin(math.radians(h)) * reach, sy + math.cos(math.radians(h)) * reach


def go_to(tx, ty):
    """Drive there: along y first, then along x, facing the way of travel."""
    if abs(ty - pose["y"]) > 0.01:
        face(0 if ty > pose["y"] else 180)
        forward(abs(ty - pose["y"]))
    if abs(tx - pose["x"]) > 0.01:
        face(270 if tx > pose["x"] else 90)
        forward(abs(tx - pose["x"]))


def find_block():
    forward(12)  # to [6, 30], just below the loading zone
    sighting = scan(90, 270, 3)  # left, up, right: most of the zone
    if sighting is None:
        forward(24)  # up to [6, 6]: nothing was seen in column 0
        sighting = scan(0, 357, 3)
    if sighting is None:
        raise SystemExit("no block found in the loading zone")
    face(sighting[0])
    return block_place(sighting)


def pick_up(bx, by):
    """Line up 7 in from the block on one side, look again closely, drive the mouth around it."""
    if by < 12:  # approach from below, facing up
        go_to(pose["x"], by + 7)
        go_to(bx, by + 7)
        approach = 180
    else:  # approach from above, facing down
        lane = min(pose["x"], bx - BLOCK / 2 - HALF_WIDTH - 0.3)  # pass the block on its left
        if pose["y"] > by and lane < TURNING:  # below it, no room to pass: come from below
            go_to(bx, pose["y"])
            approach = 180
        else:
            if pose["y"] > by:
                go_to(lane, pose["y"])
            go_to(pose["x"], by - 7)
            go_to(bx, by - 7)
            approach = 0
    for _ in range(3):  # look closely, shift sideways onto the block's line, look again
        face(approach)
        sighting = scan(approach - 20, approach + 20, 1)
        if sighting is None:
            break
        h, distance = sighting
        across = (distance + BLOCK / 2) * math.sin(math.radians(h - approach))
        if abs(across) < 0.1:
            break
        turn(90 if across > 0 else -90)
        forward(abs(across))
    face(approach)
    low = read()[1]
    forward(low - 0.2)  # until the block's near side almost touches the back of the mouth
    if send("g0-1")[0] != 1.0:
        raise SystemExit("the gripper closed on nothing")


# ---------------------------------------------------------------- phase 3: delivery


def route(start, goal):
    """Cells from start to goal through open cells (breadth first)."""
    came = {start: None}
    todo = deque([start])
    while todo:
        cell = todo.popleft()
        if cell == goal:
            break
        r, c = cell
        for near in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            nr, nc = near
            if 0 <= nr < 4 and 0 <= nc < 8 and WALLS[nr][nc] and near not in came:
                came[near] = cell
                todo.append(near)
    path = [goal]
    while came[path[-1]] is not None:
        path.append(came[path[-1]])
    return path[::-1]


def deliver(zone):
    here = (int(pose["y"] // CELL), int(pose["x"] // CELL))
    go_to((here[1] + 0.5) * CELL, (here[0] + 0.5) * CELL)
    for r, c in route(here, ZONES[zone])[1:]:
        go_to((c + 0.5) * CELL, (r + 0.5) * CELL)
    send("g0-0")
    forward(-3)


def main():
    bx, by = find_block()
    print(f"block at about [{bx:.1f}, {by:.1f}]")
    pick_up(bx, by)
    print("picked up the block")
    zone = ""
    while zone not in ZONES:
        zone = input("Enter a valid drop-off zone (B1, B2, B3, or B4): ").strip().upper()
    deliver(zone)
    print(f"delivered to {zone}")


if __name__ == "__main__":
    main()
