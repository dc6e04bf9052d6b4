"""The layout pages: choose or create a map, and the layout editor with its JSON endpoints.

They need MANAGE_LAYOUTS (fleet.roles). The editor posts the whole layout as JSON (CSRF token
in the X-CSRFToken header):
`check/` answers with the problems or the validation findings it would have, `save/` writes it
as a new version (422 with every problem, 409 when someone saved in between).
"""

import json
import mimetypes
from typing import Any

from django.http import FileResponse, Http404, HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.views.decorators.http import require_GET, require_POST

from fleet import roles
from fleet.access import require_permission
from maps.forms import NewMapForm
from maps.models import Map
from maps.selectors import editor_data, release_by_token, validate_layout
from maps.selectors.editor import list_editable_maps
from maps.services import (
    LayoutConflictError,
    LayoutPayloadError,
    check_layout_draft,
    create_layout,
    save_layout_version,
)

MAX_PAYLOAD = 32 * 1024 * 1024  # bytes: a layout of about 200,000 nodes


@require_permission(roles.MANAGE_LAYOUTS)
def layout_list(request: HttpRequest) -> HttpResponse:
    """The maps to edit, and a form for a new empty one."""
    form = NewMapForm(request.POST or None)
    if request.method == "POST" and form.is_valid():
        data = form.cleaned_data
        spec = {
            "mapId": data["map_id"],
            "name": data["name"],
            "site": data["site"],
            "level": data["level"],
            "nodes": [],
            "edges": [],
        }
        return redirect("maps:edit", pk=create_layout(spec=spec).pk)
    return render(request, "maps/list.html", {"maps": list_editable_maps(), "form": form})


@require_permission(roles.MANAGE_LAYOUTS)
def layout_editor(request: HttpRequest, pk: int) -> HttpResponse:
    """The layout editor of one map."""
    layout = get_object_or_404(Map.objects.select_related("site"), pk=pk)
    return render(request, "maps/editor.html", {"map": layout, "data": editor_data(map=layout)})


@require_POST
@require_permission(roles.MANAGE_LAYOUTS, json=True)
def layout_check(request: HttpRequest, pk: int) -> JsonResponse:
    """The problems of the posted layout, or the findings validation would report once saved."""
    layout = get_object_or_404(Map, pk=pk)
    payload, error = _payload(request)
    if error is not None:
        return error
    problems, findings = check_layout_draft(map=layout, payload=payload)
    return JsonResponse(
        {
            "problems": [p.as_dict() for p in problems],
            "findings": [f.as_dict() for f in findings],
        }
    )


@require_POST
@require_permission(roles.MANAGE_LAYOUTS, json=True)
def layout_save(request: HttpRequest, pk: int) -> JsonResponse:
    """Save the posted layout as the map's next version."""
    layout = get_object_or_404(Map, pk=pk)
    payload, error = _payload(request)
    if error is not None:
        return error
    try:
        version = save_layout_version(map=layout, payload=payload, user=request.user)
    except LayoutPayloadError as exc:
        problems = [p.as_dict() for p in exc.problems]
        return JsonResponse({"detail": str(exc), "problems": problems}, status=422)
    except LayoutConflictError as exc:
        return JsonResponse({"detail": str(exc)}, status=409)
    return JsonResponse(
        {
            "version": version.number,
            "revision": version.revision,
            "counts": version.counts,
            "findings": [f.as_dict() for f in validate_layout(map=layout)],
        }
    )


@require_permission(roles.MANAGE_LAYOUTS)
def floor_plan(request: HttpRequest, pk: int) -> FileResponse:
    """The map's floor plan image (served here, behind the login, in every mode)."""
    layout = get_object_or_404(Map, pk=pk)
    if not layout.floor_plan:
        raise Http404("this map has no floor plan")
    try:
        handle = layout.floor_plan.open("rb")
    except FileNotFoundError:
        raise Http404("the floor plan file is missing") from None
    content_type = mimetypes.guess_type(layout.floor_plan.name)[0] or "application/octet-stream"
    response = FileResponse(handle, content_type=content_type)
    response["Cache-Control"] = "private, max-age=300"
    response["X-Content-Type-Options"] = "nosniff"
    response["Content-Security-Policy"] = "default-src 'none'; style-src 'unsafe-inline'; sandbox"
    return response


def _payload(request: HttpRequest) -> tuple[Any, JsonResponse | None]:
    if not request.content_type or request.content_type != "application/json":
        return None, JsonResponse({"detail": "send the layout as application/json"}, status=415)
    body = request.read(MAX_PAYLOAD + 1)
    if len(body) > MAX_PAYLOAD:
        return None, JsonResponse({"detail": "the layout is too large"}, status=413)
    try:
        return json.loads(body), None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        return None, JsonResponse({"detail": f"not valid JSON: {exc}"}, status=400)


@require_GET
def release_file(request: HttpRequest, token: str, name: str) -> HttpResponse:
    """A released map file, for vehicles (`downloadMap`'s mapDownloadLink).

    Vehicles cannot log in, so the unguessable token in the URL is the access check; the file
    name must match too. The checksum goes along as `X-Checksum-SHA256` (also the `mapHash`).
    """
    release = release_by_token(token=token)
    if release is None or name != release.file_name:
        raise Http404("no such map release")
    response = HttpResponse(bytes(release.content), content_type="application/json")
    response["Content-Disposition"] = f'attachment; filename="{release.file_name}"'
    response["X-Checksum-SHA256"] = release.checksum
    response["X-Content-Type-Options"] = "nosniff"
    response["Cache-Control"] = "private, max-age=3600"  # a release never changes
    return response
