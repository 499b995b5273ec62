"""Segments a synthetic occupancy map with occseg and shows one slice (with matplotlib if it is
installed; otherwise it only prints). Usage: python3 segment_map.py [map.npy] [--save slice.png]"""
import sys

import numpy as np

import occseg


def synthetic_map():
    """A 48 x 64 x 64 room [z, y, x]: free space, a table-sized box, a pillar and an unseen corner."""
    rng = np.random.default_rng(7)
    m = rng.uniform(0.05, 0.25, size=(48, 64, 64)).astype(np.float32)  # noisy free space
    m[0:20, 10:30, 12:40] = rng.uniform(0.75, 0.98, size=(20, 20, 28))  # box on the floor
    m[:, 44:52, 44:52] = 0.95  # pillar
    m[:, 54:, :20] = 0.5  # never observed
    return m


def main(argv):
    save = argv[argv.index("--save") + 1] if "--save" in argv else None
    files = [a for a in argv if a.endswith(".npy")]
    with (occseg.read_map(files[0]) if files else occseg.Map.from_array(synthetic_map(), voxel_size=0.05)) as m:
        probabilities = m.to_array()
        result = occseg.segment(m, preset="default")
    with result:
        print(f"occseg {occseg.version()}: {len(result.segments)} segments in "
              f"{sum(result.timings.values()) * 1e3:.1f} ms")
        for s in result.segments:
            print(f"  segment {s.id}: {s.state.name.lower()}, {s.voxels} voxels, mop {s.mop:.2f}, "
                  f"bbox {s.bbox[0]}-{s.bbox[1]}")
        z = probabilities.shape[0] // 4
        try:
            import matplotlib
            if save:
                matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no picture")
            return
        fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4.5))
        a.imshow(probabilities[z], origin="lower", cmap="gray_r", vmin=0, vmax=1)
        a.set_title(f"occupancy probability, z = {z}")
        b.imshow(result.labels[z], origin="lower", cmap="tab20", interpolation="nearest")
        b.set_title("segments")
        for ax in (a, b):
            ax.set_xlabel("x (voxels)")
            ax.set_ylabel("y (voxels)")
        if save:
            fig.savefig(save)
            print(f"slice written to {save}")
        else:
            plt.show()


if __name__ == "__main__":
    main(sys.argv[1:])
