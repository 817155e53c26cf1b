//! One connection to a results store, whichever database holds it: an
//! SQLite file or a PostgreSQL server. Every statement of the store is
//! written once, in the SQL the two share (parameters `$1`, `$2`, ...,
//! which SQLite reads as named ones in order); what differs between them
//! is named in [`Dialect`] and in `schema.rs`.
//!
//! Values cross as [`Value`]: integers, reals, text and NULL, which is
//! all the store holds.

use super::Fault;
use postgres::fallible_iterator::FallibleIterator;
use postgres::types::{FromSql, IsNull, ToSql, Type};
use std::collections::HashMap;
use std::error::Error;

/// Which database a store is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dialect {
    Sqlite,
    Postgres,
}

/// One value of a row or a parameter.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Null,
    Int(i64),
    Real(f64),
    Text(String),
}

impl From<i64> for Value {
    fn from(v: i64) -> Value {
        Value::Int(v)
    }
}
impl From<f64> for Value {
    fn from(v: f64) -> Value {
        Value::Real(v)
    }
}
impl From<&str> for Value {
    fn from(v: &str) -> Value {
        Value::Text(v.to_string())
    }
}
impl From<String> for Value {
    fn from(v: String) -> Value {
        Value::Text(v)
    }
}
impl<T: Into<Value>> From<Option<T>> for Value {
    fn from(v: Option<T>) -> Value {
        v.map_or(Value::Null, Into::into)
    }
}

/// What went wrong in the database, and whose it is.
#[derive(Debug)]
pub(crate) struct DbError {
    pub why: String,
    pub fault: Fault,
}

impl DbError {
    pub(crate) fn new(why: impl Into<String>) -> DbError {
        DbError {
            why: why.into(),
            fault: Fault::Other,
        }
    }

    /// The store is damaged, or is none of ppmc's.
    pub(crate) fn corrupt(why: impl Into<String>) -> DbError {
        DbError {
            why: why.into(),
            fault: Fault::Store,
        }
    }
}

/// A failure of ppmc's own making (a record that does not render), not the
/// database's.
impl From<String> for DbError {
    fn from(why: String) -> DbError {
        DbError::new(why)
    }
}

impl From<rusqlite::Error> for DbError {
    fn from(e: rusqlite::Error) -> DbError {
        use rusqlite::ErrorCode as C;
        match e.sqlite_error_code() {
            Some(C::NotADatabase) => DbError::corrupt("not a results store (not an SQLite file)"),
            // The machine's trouble, not the file's.
            Some(
                C::SystemIoFailure
                | C::DatabaseBusy
                | C::DatabaseLocked
                | C::OutOfMemory
                | C::DiskFull
                | C::CannotOpen
                | C::ReadOnly
                | C::PermissionDenied
                | C::OperationInterrupted
                // A trigger or a key of the lab's refused the row.
                | C::ConstraintViolation,
            ) => DbError::new(e.to_string()),
            // Damage, a table or column gone, a value of the wrong type:
            // the store is not as ppmc made it.
            _ => DbError::corrupt(format!("the store is damaged: {e}")),
        }
    }
}

impl From<postgres::Error> for DbError {
    fn from(e: postgres::Error) -> DbError {
        // The server's own words where it gave them (`e` alone says "db
        // error"), and the cause of a lost connection.
        let why = match (e.as_db_error(), e.source()) {
            (Some(db), _) => format!("{}: {}", db.severity(), db.message()),
            (None, Some(cause)) => format!("{e}: {cause}"),
            (None, None) => e.to_string(),
        };
        // A closed connection is the link's; the server's own errors
        // about the store's tables are the store's.
        // An I/O error on the way (a connection reset by the server) is
        // the link's too.
        let io = e
            .source()
            .is_some_and(|c| c.downcast_ref::<std::io::Error>().is_some());
        let fault = match e.code() {
            _ if e.is_closed() || io => Fault::Link,
            Some(c) if c.code().starts_with("42") || c.code().starts_with("XX") => Fault::Store,
            // The connection's loss, and the server going down or
            // dropping it (57P01-57P03).
            Some(c) if c.code().starts_with("08") || c.code().starts_with("57P") => Fault::Link,
            _ => Fault::Other,
        };
        DbError { why, fault }
    }
}

/// A row as it came: its values, read by position.
#[derive(Debug)]
pub(crate) struct Row(Vec<Value>);

impl Row {
    fn at(&self, i: usize) -> Result<&Value, DbError> {
        self.0
            .get(i)
            .ok_or_else(|| DbError::new(format!("no column {i} in a row of the store")))
    }

    pub(crate) fn opt_int(&self, i: usize) -> Result<Option<i64>, DbError> {
        match self.at(i)? {
            Value::Null => Ok(None),
            Value::Int(v) => Ok(Some(*v)),
            other => Err(DbError::corrupt(format!(
                "column {i}: {other:?} where the store keeps an integer"
            ))),
        }
    }

    pub(crate) fn int(&self, i: usize) -> Result<i64, DbError> {
        self.opt_int(i)?
            .ok_or_else(|| DbError::corrupt(format!("column {i}: NULL where it holds a number")))
    }

    /// A count or a time, never below 0.
    pub(crate) fn uint(&self, i: usize) -> Result<u64, DbError> {
        let v = self.int(i)?;
        u64::try_from(v)
            .map_err(|_| DbError::corrupt(format!("column {i}: {v}, below 0 where it cannot be")))
    }

    pub(crate) fn opt_uint(&self, i: usize) -> Result<Option<u64>, DbError> {
        match self.opt_int(i)? {
            None => Ok(None),
            Some(_) => self.uint(i).map(Some),
        }
    }

    pub(crate) fn opt_text(&self, i: usize) -> Result<Option<String>, DbError> {
        match self.at(i)? {
            Value::Null => Ok(None),
            Value::Text(s) => Ok(Some(s.clone())),
            other => Err(DbError::corrupt(format!(
                "column {i}: {other:?} where the store keeps text"
            ))),
        }
    }

    pub(crate) fn text(&self, i: usize) -> Result<String, DbError> {
        self.opt_text(i)?
            .ok_or_else(|| DbError::corrupt(format!("column {i}: NULL where it holds text")))
    }
}

/// An open connection.
#[derive(Debug)]
pub(crate) enum Conn {
    Sqlite(rusqlite::Connection),
    Postgres(Box<Pg>),
}

/// A PostgreSQL client and the statements it has prepared (one round
/// trip each, once per connection).
pub(crate) struct Pg {
    pub client: postgres::Client,
    prepared: HashMap<String, postgres::Statement>,
}

impl std::fmt::Debug for Pg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pg")
            .field("prepared", &self.prepared.len())
            .finish_non_exhaustive()
    }
}

impl Pg {
    pub(crate) fn new(client: postgres::Client) -> Pg {
        Pg {
            client,
            prepared: HashMap::new(),
        }
    }

    fn statement(&mut self, sql: &str) -> Result<postgres::Statement, DbError> {
        if let Some(s) = self.prepared.get(sql) {
            return Ok(s.clone());
        }
        let s = self.client.prepare(sql)?;
        self.prepared.insert(sql.to_string(), s.clone());
        Ok(s)
    }
}

impl Conn {
    pub(crate) fn dialect(&self) -> Dialect {
        match self {
            Conn::Sqlite(_) => Dialect::Sqlite,
            Conn::Postgres(_) => Dialect::Postgres,
        }
    }

    /// Statements with no parameters and no rows, run as one.
    pub(crate) fn batch(&mut self, sql: &str) -> Result<(), DbError> {
        match self {
            Conn::Sqlite(c) => Ok(c.execute_batch(sql)?),
            Conn::Postgres(pg) => Ok(pg.client.batch_execute(sql)?),
        }
    }

    /// Runs `sql` with `params`, handing each row to `each` as it comes
    /// (a store's history does not have to fit in memory twice).
    pub(crate) fn for_each(
        &mut self,
        sql: &str,
        params: &[Value],
        mut each: impl FnMut(Row) -> Result<(), DbError>,
    ) -> Result<(), DbError> {
        match self {
            Conn::Sqlite(c) => {
                let mut st = c.prepare_cached(sql)?;
                let n = st.column_count();
                let mut rows = st.query(rusqlite::params_from_iter(params.iter()))?;
                while let Some(r) = rows.next()? {
                    let mut values = Vec::with_capacity(n);
                    for i in 0..n {
                        values.push(Value::from(r.get_ref(i)?));
                    }
                    each(Row(values))?;
                }
                Ok(())
            }
            Conn::Postgres(pg) => {
                let st = pg.statement(sql)?;
                let mut rows = pg.client.query_raw(&st, params.iter())?;
                while let Some(r) = rows.next()? {
                    let mut values = Vec::with_capacity(r.len());
                    for i in 0..r.len() {
                        values.push(r.try_get::<_, Value>(i)?);
                    }
                    each(Row(values))?;
                }
                Ok(())
            }
        }
    }

    /// Every row of `sql`.
    pub(crate) fn query(&mut self, sql: &str, params: &[Value]) -> Result<Vec<Row>, DbError> {
        let mut rows = Vec::new();
        self.for_each(sql, params, |r| {
            rows.push(r);
            Ok(())
        })?;
        Ok(rows)
    }

    /// The one row of `sql` (an aggregate, or an insert's `RETURNING`).
    pub(crate) fn row(&mut self, sql: &str, params: &[Value]) -> Result<Row, DbError> {
        self.query(sql, params)?
            .into_iter()
            .next()
            .ok_or_else(|| DbError::new(format!("no row from {sql}")))
    }

    /// Runs a statement that returns no rows.
    pub(crate) fn execute(&mut self, sql: &str, params: &[Value]) -> Result<u64, DbError> {
        match self {
            Conn::Sqlite(c) => {
                let mut st = c.prepare_cached(sql)?;
                Ok(st.execute(rusqlite::params_from_iter(params.iter()))? as u64)
            }
            Conn::Postgres(pg) => {
                let st = pg.statement(sql)?;
                let params: Vec<&(dyn ToSql + Sync)> =
                    params.iter().map(|p| p as &(dyn ToSql + Sync)).collect();
                Ok(pg.client.execute(&st, &params)?)
            }
        }
    }
}

impl From<rusqlite::types::ValueRef<'_>> for Value {
    fn from(v: rusqlite::types::ValueRef<'_>) -> Value {
        use rusqlite::types::ValueRef as V;
        match v {
            V::Null => Value::Null,
            V::Integer(i) => Value::Int(i),
            V::Real(r) => Value::Real(r),
            V::Text(t) => Value::Text(String::from_utf8_lossy(t).into_owned()),
            // The store keeps no blobs: one where text belongs reads as
            // text, and is refused where a number belongs.
            V::Blob(b) => Value::Text(String::from_utf8_lossy(b).into_owned()),
        }
    }
}

impl rusqlite::ToSql for Value {
    fn to_sql(&self) -> rusqlite::Result<rusqlite::types::ToSqlOutput<'_>> {
        use rusqlite::types::{ToSqlOutput, Value as V, ValueRef};
        Ok(match self {
            Value::Null => ToSqlOutput::Owned(V::Null),
            Value::Int(i) => ToSqlOutput::Owned(V::Integer(*i)),
            Value::Real(r) => ToSqlOutput::Owned(V::Real(*r)),
            Value::Text(t) => ToSqlOutput::Borrowed(ValueRef::Text(t.as_bytes())),
        })
    }
}

type BoxError = Box<dyn Error + Sync + Send>;

/// A parameter in the type the server asked for: the store's integers are
/// BIGINT, its reals DOUBLE PRECISION, its strings TEXT.
impl ToSql for Value {
    fn to_sql(&self, ty: &Type, out: &mut bytes::BytesMut) -> Result<IsNull, BoxError> {
        match self {
            Value::Null => Ok(IsNull::Yes),
            Value::Int(v) => match *ty {
                Type::INT8 => v.to_sql(ty, out),
                Type::INT4 => i32::try_from(*v)?.to_sql(ty, out),
                Type::INT2 => i16::try_from(*v)?.to_sql(ty, out),
                Type::BOOL => (*v != 0).to_sql(ty, out),
                Type::FLOAT8 => (*v as f64).to_sql(ty, out),
                _ => Err(format!("an integer where the server wants {ty}").into()),
            },
            Value::Real(v) => match *ty {
                Type::FLOAT8 => v.to_sql(ty, out),
                Type::FLOAT4 => (*v as f32).to_sql(ty, out),
                _ => Err(format!("a real number where the server wants {ty}").into()),
            },
            Value::Text(s) => s.as_str().to_sql(ty, out),
        }
    }

    fn accepts(_: &Type) -> bool {
        true
    }

    postgres::types::to_sql_checked!();
}

impl<'a> FromSql<'a> for Value {
    fn from_sql(ty: &Type, raw: &'a [u8]) -> Result<Value, BoxError> {
        Ok(match *ty {
            Type::INT8 => Value::Int(i64::from_sql(ty, raw)?),
            Type::INT4 => Value::Int(i32::from_sql(ty, raw)?.into()),
            Type::INT2 => Value::Int(i16::from_sql(ty, raw)?.into()),
            Type::BOOL => Value::Int(bool::from_sql(ty, raw)?.into()),
            Type::FLOAT8 => Value::Real(f64::from_sql(ty, raw)?),
            Type::FLOAT4 => Value::Real(f32::from_sql(ty, raw)?.into()),
            _ if <&str as FromSql>::accepts(ty) => Value::Text(String::from_sql(ty, raw)?),
            _ => return Err(format!("a column of type {ty}, which the store does not use").into()),
        })
    }

    fn from_sql_null(_: &Type) -> Result<Value, BoxError> {
        Ok(Value::Null)
    }

    fn accepts(_: &Type) -> bool {
        true
    }
}
