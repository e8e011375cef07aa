"""One command per paper: its tables and figures for the Go1, beside the published numbers."""
