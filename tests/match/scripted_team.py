#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# A team program for `ubersim match` tests: says what it was told (colour and ports from the
# environment), then sends a RobotControl for its six robots 60 times a second to its control port.
#   scripted_team.py play            keep sending until stopped
#   scripted_team.py crash SECONDS   send, then exit with code 3 after SECONDS
#   scripted_team.py silent          never send (a team that stopped answering)
import os
import socket
import sys
import time

sys.path.insert(0, os.environ["UBERSIM_PROTO_DIR"])
import ssl_simulation_robot_control_pb2 as rc  # noqa: E402

mode = sys.argv[1]
color = os.environ["UBERSIM_TEAM_COLOR"]
port = int(os.environ["UBERSIM_CONTROL_PORT"])
print(f"team {color} control {port} vision {os.environ['UBERSIM_VISION_PORT']} "
      f"referee {os.environ['UBERSIM_REFEREE_PORT']} args {' '.join(sys.argv[2:])}", flush=True)
if mode == "silent":
    while True:
        time.sleep(1)
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
control = rc.RobotControl()
for robot in range(6):
    c = control.robot_commands.add()
    c.id = robot
    v = c.move_command.global_velocity
    v.x, v.y, v.angular = 0.0, 0.0, 0.0
payload = control.SerializeToString()
start = time.monotonic()
while True:
    sock.sendto(payload, ("127.0.0.1", port))
    if mode == "crash" and time.monotonic() - start > float(sys.argv[2]):
        sys.exit(3)
    time.sleep(1 / 60)
