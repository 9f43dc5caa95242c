"""camera_victure: USB, file and network cameras published on Zenoh like the simulator's."""
