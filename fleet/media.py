"""Uploaded files (floor plans, work-order attachments), served to staff who may see operations.

Uploads are not public static files: a work-order photo or a floor plan says a lot about a site.
The view checks the permission, then streams the file from the default storage.
"""

from django.contrib.auth.decorators import login_required, permission_required
from django.core.exceptions import SuspiciousFileOperation
from django.core.files.storage import default_storage
from django.http import FileResponse, Http404, HttpRequest

from fleet import roles


@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def media_file(request: HttpRequest, name: str) -> FileResponse:
    """One uploaded file, if it exists inside MEDIA_ROOT."""
    try:
        if not default_storage.exists(name):
            raise Http404("no such file")
        handle = default_storage.open(name, "rb")
    except SuspiciousFileOperation as exc:  # "../" and absolute paths
        raise Http404("no such file") from exc
    response = FileResponse(handle, as_attachment=False)
    response["X-Content-Type-Options"] = "nosniff"
    response["Content-Security-Policy"] = (
        "default-src 'none'; img-src 'self'; style-src 'unsafe-inline'"
    )
    return response
