"""Turns the objects of an occupancy map into collision boxes, the plain data a MoveIt
CollisionObject with BOX primitives takes (dimensions, and a pose: position and orientation as
x, y, z, w). Usage: python3 collision_boxes.py [map.npy --voxel-size M] [--json]

Without a file it segments a synthetic 2 m x 2 m x 1 m room at 2.5 cm: a table turned by 30 degrees
and a shelf along a wall. Each occupied segment becomes one box; with ROS, each dict maps onto
moveit_msgs/CollisionObject (primitives[0].type = BOX, dimensions = size; primitive_poses[0] =
position + orientation) in the map's frame."""
import json
import sys

import numpy as np

import occseg


def synthetic_room(voxel=0.025):
    """[z, y, x] probabilities: free space, a turned table top with four legs, a shelf."""
    nz, ny, nx = 40, 80, 80
    m = np.full((nz, ny, nx), 0.1, np.float32)
    z, y, x = np.meshgrid(*(np.arange(n) + 0.5 for n in (nz, ny, nx)), indexing="ij")
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    u = c * (x - 34) + s * (y - 36)  # table axes (voxels), centre (34, 36)
    v = -s * (x - 34) + c * (y - 36)
    top = (abs(u) <= 16) & (abs(v) <= 8) & (z >= 28) & (z < 30)  # 0.8 x 0.4 m, 5 cm thick
    legs = np.zeros_like(top)
    for lu in (-14, 14):
        for lv in (-6, 6):
            legs |= (abs(u - lu) <= 1) & (abs(v - lv) <= 1) & (z < 28)
    m[top | legs] = 0.95
    m[0:36, 70:78, 10:70] = 0.9  # a shelf 1.5 m long along the far wall
    return m


def collision_boxes(result):
    """One dict per occupied segment: id, size (x, y, z edge lengths in metres along the box's
    axes), position (metres) and orientation (quaternion x, y, z, w, as geometry_msgs/Pose)."""
    out = []
    for s, b in zip(result.segments, result.boxes()):
        if s.state != occseg.State.OCCUPIED:
            continue
        w, x, y, z = b.quaternion
        out.append({"id": s.id, "voxels": s.voxels,
                    "size": [round(e, 4) for e in b.extents],
                    "position": [round(c, 4) for c in b.center],
                    "orientation": [round(q, 6) for q in (x, y, z, w)]})
    return out


def main(argv):
    files = [a for a in argv if a.endswith(".npy")]
    voxel = float(argv[argv.index("--voxel-size") + 1]) if "--voxel-size" in argv else 0.025
    data = np.load(files[0]) if files else synthetic_room(voxel)
    with occseg.segment(data, voxel_size=voxel) as r:
        boxes = collision_boxes(r)
    if "--json" in argv:
        print(json.dumps(boxes))
        return
    for b in boxes:
        print(f"box {b['id']}: {b['voxels']} voxels, size {b['size']} m at {b['position']}, "
              f"orientation (x, y, z, w) {b['orientation']}")


if __name__ == "__main__":
    main(sys.argv[1:])
