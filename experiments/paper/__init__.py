"""The paper reproduction: scene A-D replicas filmed through the real detector (Fig. 9/10, section 7)."""
