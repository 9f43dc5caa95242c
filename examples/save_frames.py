#!/usr/bin/env python
"""Save camera frames to disk: the newest frontal (and ventral) frame, a few times a second.

Frames are BGR numpy arrays, so OpenCV writes them as they are. Add ``--compressed`` on a Wi-Fi
link to receive JPEG instead of raw pixels (the publisher must offer them).

    python examples/save_frames.py [--count 10] [--rate 5] [--out frames] [--ventral]
"""

import argparse
import time
from pathlib import Path

import cv2

from dronewrapper import DroneWrapper


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--count", type=int, default=10, help="frames per camera")
    parser.add_argument("--rate", type=float, default=5.0, help="frames per second")
    parser.add_argument("--out", type=Path, default=Path("frames"), help="output folder")
    parser.add_argument("--ventral", action="store_true", help="also save the ventral camera")
    parser.add_argument("--compressed", action="store_true", help="receive JPEG (Wi-Fi links)")
    parser.add_argument("--name", default=None, help="drone namespace (default: drone)")
    parser.add_argument("--connect", default=None, help="router endpoint")
    args = parser.parse_args()

    cameras = ["frontal", "ventral"] if args.ventral else ["frontal"]
    args.out.mkdir(parents=True, exist_ok=True)
    with DroneWrapper(
        args.name, args.connect, cameras=cameras, compressed_images=args.compressed
    ) as drone:
        for camera in cameras:
            image = drone.wait_for_image(camera, timeout=10)
            print(f"{camera}: {image.shape[1]}x{image.shape[0]} frames")
        for i in range(args.count):
            for camera in cameras:
                image, stamp = drone.get_image(camera, with_stamp=True)
                path = args.out / f"{camera}_{i:04d}.png"
                cv2.imwrite(str(path), image)
                print(f"{path} (captured {time.time() - stamp:.3f} s ago)")
            time.sleep(1.0 / args.rate)


if __name__ == "__main__":
    main()
