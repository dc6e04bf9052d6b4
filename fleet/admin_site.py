"""The admin site of the fleet: entered by staff whose role works in the admin.

Administrators (every permission), technicians (maintenance records) and managers (read-only
operations records) get in; operators do not, even when someone ticked "staff status". Within the
admin the model permissions of the role's group decide what each one sees and changes.
"""

from django.contrib import admin
from django.contrib.admin.apps import AdminConfig
from django.http import HttpRequest

from fleet import roles


class FleetAdminSite(admin.AdminSite):
    """Django's admin site with the role check on entry."""

    def has_permission(self, request: HttpRequest) -> bool:
        user = request.user
        if not (user.is_active and user.is_staff):
            return False
        return bool(user.is_superuser) or any(
            user.has_perm(permission) for permission in roles.ADMIN_ENTRY_PERMISSIONS
        )


class FleetAdminConfig(AdminConfig):
    default_site = "fleet.admin_site.FleetAdminSite"
