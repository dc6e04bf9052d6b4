"""Orders: transport orders from ERP/WMS, their event timeline, dispatch and the ERP API."""
