"""Battery: chargers, charging policy, charge sessions and battery history (issue 7)."""
