#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/): real messages,
serialised by protobuf from the transports' .proto files, the viewer's commands as a page sends
them, and the shipped model files. Run it again after changing a .proto file or a model:

    /usr/bin/python3 tests/fuzz/make_corpus.py

Needs protoc and Debian's python3-protobuf. Files it does not write (crash-* regressions) stay.
"""
import glob
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
PROTO_DIR = os.path.join(SOURCE, "plugins", "transports", "proto")
CORPUS = os.path.join(HERE, "corpus")


def load_messages(out_dir):
    """Compiles the .proto files to Python in out_dir and imports them."""
    protos = sorted(glob.glob(os.path.join(PROTO_DIR, "*.proto")))
    subprocess.run(["protoc", "-I", PROTO_DIR, "--python_out=" + out_dir] + protos, check=True)
    sys.path.insert(0, out_dir)
    import grsim_packet_pb2 as grsim
    import ssl_gc_common_pb2 as common
    import ssl_simulation_control_pb2 as control
    import ssl_simulation_custom_erforce_pb2 as erforce
    import ssl_simulation_robot_control_pb2 as robot
    import ssl_simulation_synchronous_pb2 as sync
    return grsim, common, control, erforce, robot, sync


def write(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(CORPUS, target, name), "wb") as f:
        f.write(data)


def varint(n):
    out = bytearray()
    while n >= 0x80:
        out.append((n & 0x7F) | 0x80)
        n >>= 7
    out.append(n)
    return bytes(out)


def delimited(*messages):
    return b"".join(varint(len(m)) + m for m in (x.SerializeToString() for x in messages))


def grsim_seeds(grsim):
    def command(robot_id, **fields):
        c = grsim.grSim_Robot_Command(id=robot_id, kickspeedx=0, kickspeedz=0, veltangent=0, velnormal=0,
                                      velangular=0, spinner=False, wheelsspeed=False)
        for k, v in fields.items():
            setattr(c, k, v)
        return c

    p = grsim.grSim_Packet()
    p.commands.timestamp = 1.5
    p.commands.isteamyellow = False
    p.commands.robot_commands.extend([command(0, veltangent=1.0, velnormal=-0.5, velangular=2.0, spinner=True),
                                      command(1, kickspeedx=4.0), command(2, kickspeedx=3.0, kickspeedz=2.0)])
    write("grsim_packet", "commands_blue", p.SerializeToString())

    p = grsim.grSim_Packet()
    p.commands.timestamp = 0
    p.commands.isteamyellow = True
    p.commands.robot_commands.extend([command(3, wheelsspeed=True, wheel1=10, wheel2=-10, wheel3=10, wheel4=-10),
                                      command(4, wheelsspeed=True, wheel1=5, wheel2=5),
                                      command(5, wheelsspeed=True)])
    write("grsim_packet", "wheels_yellow", p.SerializeToString())

    p = grsim.grSim_Packet()
    p.replacement.ball.x = 1.0
    p.replacement.ball.y = -0.5
    p.replacement.ball.vx = 2.0
    p.replacement.robots.add(x=-2.0, y=1.0, dir=90.0, id=1, yellowteam=False)
    p.replacement.robots.add(x=2.0, y=-1.0, dir=-45.0, id=2, yellowteam=True, turnon=False)
    write("grsim_packet", "replacement", p.SerializeToString())

    p = grsim.grSim_Packet()
    p.replacement.ball.vy = 1.0
    p.replacement.robots.add(x=20.0, y=0.0, dir=0.0, id=9, yellowteam=True)
    write("grsim_packet", "replacement_rejected", p.SerializeToString())
    write("grsim_packet", "empty", b"")


def control_seeds(common, control, erforce):
    c = control.SimulatorCommand()
    b = c.control.teleport_ball
    b.x, b.y, b.z, b.vx, b.vy, b.roll = 1.0, 0.5, 0.1, 2.0, -1.0, True
    write("ssl_simulation_control", "teleport_ball", c.SerializeToString())

    c = control.SimulatorCommand()
    t = c.control.teleport_robot.add()
    t.id.id, t.id.team = 1, common.BLUE
    t.x, t.y, t.orientation, t.v_x, t.v_angular = -1.0, 1.0, 1.57, 0.5, 1.0
    t = c.control.teleport_robot.add()
    t.id.id, t.id.team = 2, common.YELLOW
    t.present = False
    c.control.simulation_speed = 2.0
    write("ssl_simulation_control", "teleport_robots_speed", c.SerializeToString())

    c = control.SimulatorCommand()
    r = erforce.RealismConfigErForce(stddev_ball_p=0.003, stddev_robot_p=0.002, stddev_robot_phi=0.01,
                                     missing_ball_detections=0.05, robot_command_loss=0.01,
                                     vision_delay=35_000_000, command_delay=10_000_000, camera_overlap=0.3,
                                     simulate_dribbling=True, stddev_ball_area=0.0)
    c.config.realism_config.custom.add().Pack(r, type_url_prefix="type.googleapis.com/")
    write("ssl_simulation_control", "realism_erforce", c.SerializeToString())

    c = control.SimulatorCommand()
    c.config.vision_port = 10020
    spec = c.config.robot_specs.add()
    spec.id.id, spec.id.team = 0, common.BLUE
    f = c.config.geometry.field
    f.field_length, f.field_width, f.goal_width, f.goal_depth, f.boundary_width = 9000, 6000, 1000, 180, 300
    write("ssl_simulation_control", "config_unsupported", c.SerializeToString())
    # A robot spec without its required id: refused as a whole (UBERSIM_MISSING_FIELD).
    c = control.SimulatorCommand()
    c.config.robot_specs.add().radius = 0.09
    write("ssl_simulation_control", "missing_required", c.SerializePartialToString())
    write("ssl_simulation_control", "empty", b"")


def robot_control_message(robot):
    m = robot.RobotControl()
    c = m.robot_commands.add(id=0, kick_speed=5.0, kick_angle=30.0, dribbler_speed=1000.0)
    c.move_command.local_velocity.forward, c.move_command.local_velocity.left = 1.0, 0.5
    c.move_command.local_velocity.angular = 1.0
    c = m.robot_commands.add(id=1)
    c.move_command.global_velocity.x, c.move_command.global_velocity.y = -1.0, 0.0
    c.move_command.global_velocity.angular = 0.0
    c = m.robot_commands.add(id=2)
    w = c.move_command.wheel_velocity
    w.front_right, w.back_right, w.back_left, w.front_left = 10.0, -10.0, -10.0, 10.0
    return m


def robot_control_seeds(robot):
    write("ssl_simulation_robot_control", "three_robots", robot_control_message(robot).SerializeToString())
    m = robot.RobotControl()
    m.robot_commands.add(id=9, kick_speed=1.0)
    m.robot_commands.add(id=9)
    write("ssl_simulation_robot_control", "unknown_robot", m.SerializeToString())
    write("ssl_simulation_robot_control", "empty", b"")


def sync_seeds(common, control, robot, sync):
    step = sync.SimulationSyncRequest(sim_step=0.016)
    step.robot_control.CopyFrom(robot_control_message(robot))
    place = sync.SimulationSyncRequest(sim_step=0.0)
    b = place.simulator_command.control.teleport_ball
    b.x, b.y = 0.0, 0.0
    t = place.simulator_command.control.teleport_robot.add()
    t.id.id, t.id.team = 0, common.BLUE
    t.x, t.y = -1.0, 0.0
    write("ssl_simulation_sync", "place_then_step", delimited(place, step, step))
    write("ssl_simulation_sync", "empty_request", delimited(sync.SimulationSyncRequest()))
    # A frame, then half of the next one: the connection waits for the rest.
    write("ssl_simulation_sync", "partial_frame", delimited(step) + delimited(step)[:7])
    # A length prefix that never ends: the connection is closed.
    write("ssl_simulation_sync", "endless_prefix", delimited(step) + b"\xff" * 6)


def viewer_seeds():
    commands = {
        "pause": '{"cmd": "pause", "id": 1}',
        "resume": '{"cmd": "resume", "id": 2}',
        "step": '{"cmd": "step", "steps": 10, "id": 3}',
        "speed": '{"cmd": "speed", "factor": 0.5, "id": 4}',
        "reset": '{"cmd": "reset"}',
        "move_ball": '{"cmd": "move", "target": "ball", "x": 1.0, "y": -0.5, "z": 0.0, "id": 5}',
        "move_robot": '{"cmd": "move", "target": {"team": "yellow", "id": 3}, "x": -2.0, "y": 1.0, "yaw": 1.57}',
        "kick": '{"cmd": "kick", "vx": 3.0, "vy": 1.0, "vz": 0.5, "id": 6}',
        "unknown": '{"cmd": "jump", "id": -7}',
        "not_an_object": '[1, 2, "three", null, true, {"a": {}}]',
    }
    for name, text in commands.items():
        write("viewer_command", name, text)


def model_seeds():
    for path in sorted(glob.glob(os.path.join(SOURCE, "models", "*", "*.yaml"))):
        kind = os.path.basename(os.path.dirname(path))
        shutil.copyfile(path, os.path.join(CORPUS, "model_loader", kind + "_" + os.path.basename(path)))


def main():
    with tempfile.TemporaryDirectory() as tmp:
        grsim, common, control, erforce, robot, sync = load_messages(tmp)
        grsim_seeds(grsim)
        control_seeds(common, control, erforce)
        robot_control_seeds(robot)
        sync_seeds(common, control, robot, sync)
    viewer_seeds()
    os.makedirs(os.path.join(CORPUS, "model_loader"), exist_ok=True)
    model_seeds()


if __name__ == "__main__":
    main()
