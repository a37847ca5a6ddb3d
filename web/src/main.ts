// Entry point of the SFC Editor (the app shell in src/app mounts everything).
