"""`auvdiag audit`: many logs, one table and one fleet PDF; resumable and parallel."""
