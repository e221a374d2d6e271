"""What amronet writes: output folders and files, written atomically and never over a user's files."""
