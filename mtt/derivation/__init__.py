"""Bond graph -> causal bond graph -> equations -> transfer function -> Theta, exactly."""
