"""Monte-Carlo engine: batched missions, the paper's metrics, tables and reports."""
