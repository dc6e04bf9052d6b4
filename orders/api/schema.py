"""OpenAPI post-processing: the error answers every operation can give, documented once."""

from typing import Any

ERROR = {
    "type": "object",
    "properties": {"detail": {"type": "string"}},
    "required": ["detail"],
}
FIELD_ERRORS = {
    "type": "object",
    "description": "Per field (or `non_field_errors`), the list of what is wrong.",
    "additionalProperties": {},
}


def _error(description: str, schema: dict[str, Any]) -> dict[str, Any]:
    return {"description": description, "content": {"application/json": {"schema": schema}}}


def add_error_responses(result: dict[str, Any], **kwargs: Any) -> dict[str, Any]:
    """Add 400 (bad input), 401 (no or bad credentials) and 404 (unknown id) where they apply,
    without touching answers a view documents itself."""
    for path, operations in result.get("paths", {}).items():
        for operation in operations.values():
            if not isinstance(operation, dict) or "responses" not in operation:
                continue
            responses = operation["responses"]
            takes_input = "requestBody" in operation or any(
                p.get("in") == "query" for p in operation.get("parameters", [])
            )
            if takes_input or any(p.get("in") == "header" for p in operation.get("parameters", [])):
                responses.setdefault("400", _error("Invalid input.", FIELD_ERRORS))
            if operation.get("security") != [{}]:
                responses.setdefault("401", _error("No, wrong or expired credentials.", ERROR))
            if "{" in path:
                responses.setdefault("404", _error("No such object.", ERROR))
    return result
